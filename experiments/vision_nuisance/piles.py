#!/usr/bin/env python3
"""piles.py: the piles of the vision nuisance set, as small CSV files of grains.

Design note. The nuisance set photographs piles that vision/ has never been tuned on: two of the
twin (`reposetwin run` on small scenes, its final.vtp) and one of LIGGGHTS 3.8 (a pour from a
point source onto a plate, a deck written here, not the twin's `export`, so that neither the
procedure nor the code is the twin's). Each pile is stored as x,y,z,r in metres with the pile axis
on the z axis and the plate's top face at z = 0, under a '#' provenance line saying how it was
made (scene, seed, code version, engine version). The photos are rendered from these files only
(render.py), so the CSVs, not the runs, are what the set depends on.

Standard library only. Usage:
  piles.py twin --bin BIN --scene SCENE|quick --seed S --out DIR --name NAME [--set k=v ...]
  piles.py liggghts --seed S --out DIR --name NAME [--n 2000] [--mu-r 0.3]
  piles.py vtp FILE.vtp OUT.csv     (convert a snapshot only)
"""
import argparse
import base64
import datetime
import math
import os
import re
import struct
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
PLATE_HALF_M = 0.25  # the plate the photos show (render.py): grains beyond it fell off it


# ---------------------------------------------------------------------------------------------
# VTK XML PolyData reader (appended raw data, optionally zlib-compressed; the twin's final.vtp)

def _read_vtp(path):
    """Returns {'points': [(x, y, z)], name: [values]} for the point data arrays of a .vtp."""
    with open(path, "rb") as f:
        blob = f.read()
    start = blob.find(b"<AppendedData")
    if start < 0:
        raise ValueError(path + ": no <AppendedData> (only appended raw .vtp files are read)")
    us = blob.find(b"_", blob.find(b">", start)) + 1
    head = blob[:start].decode("utf-8", "replace") + "</VTKFile>"
    # The header closes the PolyData/Piece elements that were opened before AppendedData.
    head = head.replace("</VTKFile>", "")
    for tag in ("Piece", "PolyData"):
        if ("<" + tag) in head and ("</" + tag + ">") not in head:
            head += "</" + tag + ">"
    head += "</VTKFile>"
    root = ET.fromstring(head)
    header_type = root.get("header_type", "UInt32")
    compressed = root.get("compressor") is not None
    hfmt, hsize = ("<Q", 8) if header_type == "UInt64" else ("<I", 4)
    if root.get("byte_order", "LittleEndian") != "LittleEndian":
        raise ValueError(path + ": big-endian .vtp not supported")
    types = {"Float64": ("d", 8), "Float32": ("f", 4), "Int64": ("q", 8), "Int32": ("i", 4),
             "UInt64": ("Q", 8), "UInt32": ("I", 4), "UInt8": ("B", 1), "Int8": ("b", 1)}

    def payload(offset):
        p = us + offset
        if not compressed:
            (n,) = struct.unpack(hfmt, blob[p:p + hsize])
            return blob[p + hsize:p + hsize + n]
        (nb,) = struct.unpack(hfmt, blob[p:p + hsize])
        sizes = struct.unpack("<" + hfmt[1] * (nb + 2), blob[p + hsize:p + hsize * (nb + 3)])
        comp = sizes[2:]
        q = p + hsize * (nb + 3)
        out = b""
        for c in comp:
            out += zlib.decompress(blob[q:q + c])
            q += c
        return out

    def array(el):
        code, size = types[el.get("type")]
        data = payload(int(el.get("offset")))
        n = len(data) // size
        return list(struct.unpack("<" + code * n, data)), int(el.get("NumberOfComponents", "1"))

    piece = root.find(".//Piece")
    pts_el = piece.find("Points/DataArray")
    vals, nc = array(pts_el)
    pts = [tuple(vals[i:i + 3]) for i in range(0, len(vals), nc)]
    out = {"points": pts}
    for el in piece.findall("PointData/DataArray"):
        v, ncomp = array(el)
        if ncomp == 1:
            out[el.get("Name")] = v
    return out


def _write_csv(path, grains, provenance):
    """grains: [(x, y, z, r)] with the plate top at z = 0 and the axis at x = y = 0."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("# " + provenance.replace("\n", " ") + "\n")
        f.write("x_m,y_m,z_m,r_m\n")
        for x, y, z, r in grains:
            f.write("%.6f,%.6f,%.6f,%.6f\n" % (x, y, z, r))
    os.replace(tmp, path)


def _centre_and_clip(grains, z_plate=0.0):
    """Keeps grains resting on the plate (centre above it, within the plate's square); centres the
    pile's axis at the grains' mass-weighted centre of the lower layers (x, y), keeps z."""
    g = [(x, y, z - z_plate, r) for x, y, z, r in grains if z - z_plate > 0.0]
    w = [r ** 3 for *_, r in g]
    sw = sum(w)
    cx = sum(wi * gi[0] for wi, gi in zip(w, g)) / sw
    cy = sum(wi * gi[1] for wi, gi in zip(w, g)) / sw
    g = [(x - cx, y - cy, z, r) for x, y, z, r in g]
    kept = [t for t in g if abs(t[0]) + t[3] < PLATE_HALF_M and abs(t[1]) + t[3] < PLATE_HALF_M]
    return kept, (cx, cy), len(g) - len(kept)


def _summary(grains):
    h = max(z + r for _, _, z, r in grains)
    rad = sorted(math.hypot(x, y) + r for x, y, _, r in grains)
    r95 = rad[int(0.95 * (len(rad) - 1))]
    rmax = rad[-1]
    return h, r95, rmax


# ---------------------------------------------------------------------------------------------
# The twin's piles

def twin(args):
    os.makedirs(args.out, exist_ok=True)
    run_dir = os.path.join(args.out, args.name + "_run")
    cmd = ["nice", "-n", "19", args.bin, "run"]
    if args.scene != "quick":
        cmd.append(args.scene)
    cmd += ["--out", run_dir, "--no-images", "--yes", "--force",
            "--set", "scene.seed=%d" % args.seed]
    for s in args.set or []:
        cmd += ["--set", s]
    env = dict(os.environ, OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive")
    t0 = time.time()
    log = open(os.path.join(args.out, args.name + "_run.log"), "w")
    rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)
    wall = time.time() - t0
    vtp = os.path.join(run_dir, "final.vtp")
    if not os.path.exists(vtp):
        sys.exit("piles.py: %s wrote no final.vtp (exit %d); see %s" % (" ".join(cmd), rc, log.name))
    version = subprocess.run([args.bin, "--version"], capture_output=True, text=True).stdout.strip()
    d = _read_vtp(vtp)
    grains = [(x, y, z, r) for (x, y, z), r in zip(d["points"], d["radius"])]
    kept, centre, dropped = _centre_and_clip(grains)
    h, r95, rmax = _summary(kept)
    prov = ("pile %s: the twin, `reposetwin run %s --set scene.seed=%d%s --no-images` (%s, exit %d, "
            "wall %.0f s); final.vtp's %d grains, %d kept on the 0.5 m plate, axis moved by "
            "(%.2f, %.2f) mm; H %.1f mm, r95 %.1f mm; made %s" % (
                args.name, args.scene, args.seed,
                "".join(" --set " + s for s in (args.set or [])), version, rc, wall, len(grains),
                len(kept), 1e3 * centre[0], 1e3 * centre[1], 1e3 * h, 1e3 * r95,
                datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ")))
    _write_csv(os.path.join(args.csv_dir, args.name + ".csv"), kept, prov)
    print(prov)


# ---------------------------------------------------------------------------------------------
# LIGGGHTS: a pour from a point source onto an infinite plate (no funnel, no lift)

LIGGGHTS_DECK = """# LIGGGHTS 3.8 deck written by experiments/vision_nuisance/piles.py: a pour of {n} spheres from
# a narrow source {src_lo}-{src_hi} m above a plate, then a settle. Not the twin's procedure.
atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
units si
region domain block -{half} {half} -{half} {half} -0.005 0.2 units box
create_box 2 domain
neighbor {skin} bin
neigh_modify delay 0
fix m1 all property/global youngsModulus peratomtype {E} {E}
fix m2 all property/global poissonsRatio peratomtype 0.25 0.25
fix m3 all property/global coefficientRestitution peratomtypepair 2 0.5 0.5 0.5 0.5
fix m4 all property/global coefficientFriction peratomtypepair 2 {mu} {mu} {mu} {mu}
fix m5 all property/global coefficientRollingFriction peratomtypepair 2 {mu_r} {mu_r} {mu_r} {mu_r}
pair_style gran model hertz tangential history rolling_friction epsd2
pair_coeff * *
timestep {dt}
fix gravi all gravity 9.81 vector 0.0 0.0 -1.0
fix plate all wall/gran model hertz tangential history rolling_friction epsd2 primitive type 2 zplane 0.0
fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant 2700 radius constant {r1}
fix pts2 all particletemplate/sphere 20433971 atom_type 1 density constant 2700 radius constant {r2}
fix pts3 all particletemplate/sphere 32452843 atom_type 1 density constant 2700 radius constant {r3}
fix pdd all particledistribution/discrete/numberbased 49979687 3 pts1 {f1} pts2 {f2} pts3 {f3}
region src cylinder z 0 0 {src_r} {src_lo} {src_hi} units box
fix ins all insert/rate/region seed {seed} distributiontemplate pdd nparticles {n} particlerate {rate} insert_every {every} overlapcheck yes vel constant 0 0 -0.3 region src ntry_mc 10000
fix integr all nve/sphere
thermo_style custom step atoms ke
thermo_modify lost ignore norm no
thermo {thermo}
run {pour_steps}
run {settle_steps}
write_dump all custom final.dump id type x y z radius
"""


def _prime_seed(k):
    # LIGGGHTS wants primes above 10000 for its seeds.
    n = 10007 + 1000 * k
    while any(n % p == 0 for p in range(2, int(n ** 0.5) + 1)):
        n += 1
    return n


def liggghts(args):
    work = os.path.join(args.out, args.name + "_liggghts")
    os.makedirs(work, exist_ok=True)
    dt = 2e-5
    pour_s = args.n / args.rate
    every = 2000  # steps between insertions
    deck = LIGGGHTS_DECK.format(
        n=args.n, half=PLATE_HALF_M, skin=0.002, E=1e7, mu=0.5, mu_r=args.mu_r, dt=dt,
        r1=0.0015, r2=0.002, r3=0.0025, f1=0.4, f2=0.35, f3=0.25,
        src_r=0.008, src_lo=0.05, src_hi=0.09, seed=_prime_seed(args.seed), rate=args.rate,
        every=every, thermo=10000, pour_steps=int(round(pour_s / dt)) + 2 * every,
        settle_steps=int(round(args.settle / dt)))
    with open(os.path.join(work, "in.pour"), "w") as f:
        f.write(deck)
    t0 = time.time()
    with open(os.path.join(work, "liggghts.log"), "w") as log:
        rc = subprocess.call(["nice", "-n", "19", "liggghts", "-in", "in.pour"], cwd=work,
                             stdout=log, stderr=subprocess.STDOUT)
    wall = time.time() - t0
    dump = os.path.join(work, "final.dump")
    if rc != 0 or not os.path.exists(dump):
        sys.exit("piles.py: LIGGGHTS failed (exit %d): %s/liggghts.log" % (rc, work))
    grains = []
    with open(dump) as f:
        lines = f.read().splitlines()
    i = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    cols = lines[i].split()[2:]
    ix, iy, iz, ir = (cols.index(c) for c in ("x", "y", "z", "radius"))
    for l in lines[i + 1:]:
        v = l.split()
        if len(v) == len(cols):
            grains.append((float(v[ix]), float(v[iy]), float(v[iz]), float(v[ir])))
    kept, centre, dropped = _centre_and_clip(grains)
    h, r95, rmax = _summary(kept)
    with open(os.path.join(work, "liggghts.log")) as f:
        ver = next((l.strip() for l in f if l.startswith("LIGGGHTS")), "LIGGGHTS (version unknown)")
    dpkg = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "liggghts"], capture_output=True,
                          text=True).stdout.strip()
    prov = ("pile %s: LIGGGHTS pour, deck by experiments/vision_nuisance/piles.py (%d spheres d 3/4/5 mm, "
            "E 1e7 Pa, e 0.5, mu 0.5, mu_r %.2f epsd2, source r 8 mm at 50-90 mm, %.0f grains/s, "
            "settle %.1f s, seed %d); %s (Debian liggghts %s), serial, wall %.0f s; %d grains, %d on "
            "the plate; H %.1f mm, r95 %.1f mm; made %s" % (
                args.name, args.n, args.mu_r, args.rate, args.settle, args.seed, ver, dpkg, wall,
                len(grains), len(kept), 1e3 * h, 1e3 * r95,
                datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ")))
    _write_csv(os.path.join(args.csv_dir, args.name + ".csv"), kept, prov)
    print(prov)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("twin")
    t.add_argument("--bin", required=True)
    t.add_argument("--scene", default="quick")
    t.add_argument("--seed", type=int, default=1)
    t.add_argument("--set", action="append")
    l = sub.add_parser("liggghts")
    l.add_argument("--seed", type=int, default=1)
    l.add_argument("--n", type=int, default=2000)
    l.add_argument("--rate", type=float, default=1000.0, help="grains per second")
    l.add_argument("--settle", type=float, default=1.0, help="settle time after the pour [s]")
    l.add_argument("--mu-r", type=float, default=0.3)
    for p in (t, l):
        p.add_argument("--out", required=True, help="work folder for the runs")
        p.add_argument("--name", required=True)
        p.add_argument("--csv-dir", default=os.path.join(ROOT, "results", "vision_nuisance", "piles"))
    v = sub.add_parser("vtp")
    v.add_argument("vtp")
    v.add_argument("csv")
    a = ap.parse_args()
    if a.cmd == "twin":
        twin(a)
    elif a.cmd == "liggghts":
        liggghts(a)
    else:
        d = _read_vtp(a.vtp)
        grains = [(x, y, z, r) for (x, y, z), r in zip(d["points"], d["radius"])]
        kept, centre, dropped = _centre_and_clip(grains)
        _write_csv(a.csv, kept, "converted from " + a.vtp)


if __name__ == "__main__":
    main()
