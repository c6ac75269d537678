# Yade script written by bench_clumps --collapse: its settled bed (bed.txt) released
# on the plate (the container removed at t = 0), Hertz-Mindlin as the twin's (README of
# results/studies/clump_yade_check lists what differs); writes final.dump (x y z
# radius of every sphere). Run in this folder: yade -j1 -n -x collapse.py
import math, os, time
E, NU, DENSITY, E_REST, MU_S, MU_S_PLATE = 46800000, 0.19, 2760, 0.79000000000000004, 0.46600000000000003, 0.46600000000000003
DT, SKIN, STEPS = 4.1009147583505221e-06, 0.00025000000000000001, 70000
here = os.getcwd()  # run in its folder: Yade's __file__ names the yade binary
rock = O.materials.append(FrictMat(young=E, poisson=NU, density=DENSITY,
                                   frictionAngle=math.atan(MU_S), label='rock'))
# Yade's wall contact takes the wall as a sphere of the grain's radius (R* = r/2, the twin's
# plate R* = r). A plate of E_w = (1 + sqrt 2) E gives Yade's Ip2 the twin's E* sqrt(R*), hence
# the twin's Hertz spring; its tangential spring then also equals the twin's 8 G* sqrt(R* delta)
# (both checked on one contact against the closed forms).
plate_mat = O.materials.append(FrictMat(young=(1 + math.sqrt(2)) * E, poisson=NU,
                                        density=DENSITY, frictionAngle=math.atan(MU_S_PLATE),
                                        label='plate'))
O.bodies.append(wall((0, 0, 0), axis=2, sense=1, material=plate_mat))
# The twin's damping (EDEM, Tsuji): c = 2 sqrt(5/6) |beta| sqrt(S m*) with S = 2 E* sqrt(R* delta)
# normal and 8 G* sqrt(R* delta) tangential, beta = ln e / sqrt(ln^2 e + pi^2). Yade's Law2 damps
# with 2 beta_n sqrt(k_n m*) and 2 beta_s sqrt(k_s m*), k_n = 3/2 kno sqrt(delta) = S_n and
# k_s = S_t, so beta_n = beta_s = sqrt(5/6) |beta| gives the same dashpots. (Its en = e would
# give beta_n 0.0719 at e 0.79, 5% above the twin's 0.0683.)
LOG_E = math.log(E_REST)
BETA = math.sqrt(5.0 / 6.0) * -LOG_E / math.sqrt(LOG_E ** 2 + math.pi ** 2)
clumps = spheres = 0
with open(os.path.join(here, 'bed.txt')) as bed:
    for line in bed:
        if line.startswith('#'):
            continue
        v = [float(t) for t in line.split()]
        n = int(v[10])
        balls = [sphere((v[11 + 4 * i], v[12 + 4 * i], v[13 + 4 * i]), v[14 + 4 * i],
                        material=rock) for i in range(n)]
        if n == 1:
            O.bodies.append(balls[0])
            s = balls[0].state
        else:
            cid, ids = O.bodies.appendClumped(balls)
            s = O.bodies[cid].state
            # The twin's contact damping uses m* of the bodies (a component carries its clump's
            # mass); Yade's Law2 reads the member's own state.mass, which nothing else uses once
            # the clump is built, so the members are given the clump's mass.
            for i in ids:
                O.bodies[i].state.mass = v[6]
            clumps += 1
        # Mass and principal moments of the union of the spheres, as the twin's (Yade's default
        # sums the members' own, counting overlaps twice); a tetrahedral clump's inertia is
        # isotropic up to the integration error, so the principal frame Yade chose does not matter.
        s.mass = v[6]
        s.inertia = Vector3(v[7], v[8], v[9])
        s.vel = Vector3(v[0], v[1], v[2])
        s.angVel = Vector3(v[3], v[4], v[5])
        spheres += n
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()], verletDist=SKIN),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_MindlinPhys(betan=BETA, betas=BETA)],
        [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.0, gravity=(0, 0, -9.81)),
]
O.dt = DT
def dump(name):  # every sphere as a LAMMPS-style dump "x y z radius", written atomically
    rows = ['%.17g %.17g %.17g %.17g' % (b.state.pos[0], b.state.pos[1], b.state.pos[2],
                                         b.shape.radius)
            for b in O.bodies if isinstance(b.shape, Sphere)]
    with open(os.path.join(here, name + '.tmp'), 'w') as f:
        f.write('ITEM: TIMESTEP\n%d\nITEM: NUMBER OF ATOMS\n%d\nITEM: ATOMS x y z radius\n'
                % (O.iter, len(rows)))
        f.write('\n'.join(rows) + '\n')
    os.replace(os.path.join(here, name + '.tmp'), os.path.join(here, name))
dump('initial.dump')  # Yade's bed as built, to check it against bed.txt
t0, c0 = time.perf_counter(), time.process_time()
O.run(STEPS, True)
seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
dump('final.dump')
ke = sum(0.5 * b.state.mass * b.state.vel.squaredNorm() for b in O.bodies
         if b.isClump or (isinstance(b.shape, Sphere) and not b.isClumpMember))
print('YADE_COLLAPSE clumps=%d spheres=%d steps=%d seconds=%.6g cpu_seconds=%.6g ke_end=%.6g'
      % (clumps, spheres, O.iter, seconds, cpu, ke))
