# yade_contact_check.py: checks that Yade, set up as bench_clumps' collapse.py sets it up, gives
# the twin's contact law on one contact: the Hertz normal force 4/3 E* sqrt(R*) delta^1.5, the
# tangential stiffness 8 G* sqrt(R* delta) and the normal dashpot 2 sqrt(5/6) |beta| sqrt(S_n m*)
# (sim/contact.hpp), for a sphere on another sphere (R* = r/2) and on the plate (R* = r, which
# Yade reaches only with the plate's E set to (1 + sqrt 2) E). The closed forms are written here
# from the twin's documented law, not read from either engine. Run: yade -j1 -n -x THIS; prints
# one CHECK line per quantity and "YADE_CONTACT_CHECK ok" or exits non-zero naming the failure.
# With COLLAPSE_PY=PATH in the environment, E, nu, density, e and mu_s are read from that
# collapse.py (its first assignment line); bench_clumps' physics otherwise.
import math
import os
import re
import sys

E, NU, DENSITY, E_REST, MU_S = 46.8e6, 0.19, 2760.0, 0.79, 0.466  # bench_clumps' physics
if os.environ.get('COLLAPSE_PY'):
    with open(os.environ['COLLAPSE_PY']) as f:
        line = re.search(r'^E, NU, DENSITY, E_REST, MU_S, MU_S_PLATE = (.*)$', f.read(), re.M)
    if not line:
        sys.exit('YADE_CONTACT_CHECK: %s has no "E, NU, DENSITY, E_REST, MU_S, MU_S_PLATE =" line'
                 % os.environ['COLLAPSE_PY'])
    E, NU, DENSITY, E_REST, MU_S = [float(t) for t in line.group(1).split(',')][:5]
print('YADE_CONTACT_CHECK E %.6g nu %.6g density %.6g e %.6g mu_s %.6g' % (E, NU, DENSITY, E_REST,
                                                                           MU_S))
R = 0.55e-3
LOG_E = math.log(E_REST)
BETA = math.sqrt(5.0 / 6.0) * -LOG_E / math.sqrt(LOG_E ** 2 + math.pi ** 2)  # as collapse.py
E_STAR = E / (2.0 * (1.0 - NU ** 2))            # two equal materials
G_STAR = E / (2.0 * (1.0 + NU)) / (2.0 * (2.0 - NU))
rock = O.materials.append(FrictMat(young=E, poisson=NU, density=DENSITY,
                                   frictionAngle=math.atan(MU_S)))
plate = O.materials.append(FrictMat(young=(1 + math.sqrt(2)) * E, poisson=NU, density=DENSITY,
                                    frictionAngle=math.atan(MU_S)))
O.bodies.append(wall((0, 0, 0), axis=2, sense=1, material=plate))
on_plate = sphere((0, 0, 0.999 * R), R, material=rock)           # 0.1% overlap with the plate
far = 0.1
below = sphere((far, 0, R), R, material=rock)
above = sphere((far, 0, 3 * R - 0.002 * R), R, material=rock)   # 0.2% overlap with `below`
for b in (on_plate, below, above):
    O.bodies.append(b)
on_plate.state.vel = Vector3(0, 0, -0.05)
above.state.vel = Vector3(0, 0, -0.05)
# Two clumps of two spheres, one on the other, their members given the clump's mass as
# collapse.py does: the dashpot must use m* of the clumps, as the twin's components carry.
far2 = 0.2
ca, ia = O.bodies.appendClumped([sphere((far2, 0, R), R, material=rock),
                                 sphere((far2 + 1.2 * R, 0, R), R, material=rock)])
cb, ib = O.bodies.appendClumped([sphere((far2, 0, 3 * R - 0.002 * R), R, material=rock),
                                 sphere((far2, 1.2 * R, 3 * R - 0.002 * R), R, material=rock),
                                 sphere((far2, 0, 4.2 * R - 0.002 * R), R, material=rock)])
for c, ids in ((ca, ia), (cb, ib)):
    for k in ids:
        O.bodies[k].state.mass = O.bodies[c].state.mass
O.bodies[cb].state.vel = Vector3(0, 0, -0.05)
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                    [Ip2_FrictMat_FrictMat_MindlinPhys(betan=BETA, betas=BETA)],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.0, gravity=(0, 0, 0)),
]
O.dt = 1e-9  # the velocities barely change over the step: the dashpot sees the set speed
O.run(2, True)  # the first step moves the clumps' members with the clumps' velocities
failures = []


def check(what, got, want, tol):
    rel = abs(got - want) / abs(want)
    print('CHECK %-32s yade %.9g  closed form %.9g  rel %.2e' % (what, got, want, rel))
    if not rel <= tol:
        failures.append(what)


for name, a, b, r_eff, m_eff in (('sphere-plate', 0, on_plate.id, R, on_plate.state.mass),
                                 ('sphere-sphere', below.id, above.id, R / 2,
                                  below.state.mass / 2),
                                 ('clump-clump', ia[0], ib[0], R / 2,
                                  O.bodies[ca].state.mass * O.bodies[cb].state.mass /
                                  (O.bodies[ca].state.mass + O.bodies[cb].state.mass))):
    i = O.interactions[a, b]
    d = i.geom.penetrationDepth
    s_n = 2 * E_STAR * math.sqrt(r_eff * d)
    # Yade's normalForce holds the spring and the dashpot; the spring alone is their difference.
    check(name + ' Hertz force', i.phys.normalForce.norm() - i.phys.normalViscous.norm(),
          4.0 / 3.0 * E_STAR * math.sqrt(r_eff) * d ** 1.5, 1e-9)
    check(name + ' k_t', i.phys.ks, 8 * G_STAR * math.sqrt(r_eff * d), 1e-12)
    check(name + ' normal dashpot', i.phys.normalViscous.norm(),
          2 * BETA * math.sqrt(s_n * m_eff) * 0.05, 1e-3)
if failures:
    sys.exit('YADE_CONTACT_CHECK failed: ' + ', '.join(failures))
print('YADE_CONTACT_CHECK ok')
