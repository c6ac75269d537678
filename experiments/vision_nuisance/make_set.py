#!/usr/bin/env python3
"""make_set.py: the nuisance set's manifest (the rules, written before any photo is measured) and
its photos, rendered by POV-Ray through render.py's restatement of the project's camera.

  make_set.py manifest [--piles DIR] [--out manifest.csv]   the manifest from the rules below
  make_set.py render --manifest manifest.csv --out DIR [--only ID,...] [--jobs N]
  make_set.py check --out DIR                                the camera check (< 0.5 px)

The rules (README.md says the same in words):
  - Each pile P has H (its highest grain's top), R (the 95th percentile of the grains' distance
    from the axis plus radius) and R_max (the farthest grain). Every camera stands 12 R from its
    aim point (the project's side views' distance); the image width spans
    F = max(3.2 R, 2.2 R_max) at the aim point, so that every grain on the plate is in frame.
  - The reference photo: level camera at plate height (aim (0, 0, 0), pitch 0, roll 0), the
    rock palette, even light, plain light backdrop, 1920x1080 PNG.
  - Every other photo of a pile is compared with that pile's reference photo, and every photo
    whose sidecar is truthful, whose pile is whole in frame and unobstructed, is expected
    measured ("measure"); the planted failures are expected refused by the check named.
"""
import argparse
import concurrent.futures
import csv
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import render  # noqa: E402

ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
PILES_DIR = os.path.join(ROOT, "results", "vision_nuisance", "piles")
PILES = ["twin_quick", "twin_skirt", "liggghts_pour", "liggghts_pour_b"]
SHORT = {"twin_quick": "tq", "twin_skirt": "ts", "liggghts_pour": "lp", "liggghts_pour_b": "lb"}
FIELDS = ["id", "pile", "nuisance", "pitch_deg", "roll_deg", "aim_x_m", "aim_z_m", "distance_m",
          "camera_height_m", "field_width_m", "width_px", "height_px", "grains", "light",
          "backdrop", "extra", "post", "sidecar", "declared_pitch_deg", "declared_height_m",
          "expected", "reference", "render_key"]


def geometry(pile):
    grains, _ = render.read_pile(os.path.join(PILES_DIR, pile + ".csv"))
    h, r = render.pile_size(grains)
    rmax = max(math.hypot(x, y) + rr for x, y, _, rr in grains)
    return h, r, rmax


def photo_rows(pile, short, h, r, rmax):
    L = 12.0 * r
    F = max(3.2 * r, 2.2 * rmax)
    rows = []

    def add(id_, nuisance, pitch=0.0, roll=0.0, aim_z=0.0, aim_x=0.0, field=F, grains="rock",
            light="even", backdrop="plain", extra="", post="png", size=(1920, 1080),
            declared=None, expected="measure", reference=True):
        cam = render.pose_camera(pitch, roll, aim_z, L, field, size[0], size[1], aim_x=aim_x)
        dp, dh = pitch, cam.position[2]
        sidecar = "truthful"
        if declared is not None:
            sidecar = "contradicted"
            dp, daim = declared
            dcam = render.pose_camera(dp, 0.0, daim, L, field, size[0], size[1])
            dh = dcam.position[2]
        key = "|".join(str(v) for v in (pile, pitch, roll, aim_z, aim_x, field, grains, light,
                                         backdrop, extra, size[0] if size[0] > 1920 else 1920))
        rows.append({
            "id": "%s_%s" % (short, id_), "pile": pile, "nuisance": nuisance,
            "pitch_deg": pitch, "roll_deg": roll, "aim_x_m": round(aim_x, 5),
            "aim_z_m": round(aim_z, 5), "distance_m": round(L, 5),
            "camera_height_m": round(cam.position[2], 5), "field_width_m": round(field, 5),
            "width_px": size[0], "height_px": size[1], "grains": grains, "light": light,
            "backdrop": backdrop, "extra": extra, "post": post, "sidecar": sidecar,
            "declared_pitch_deg": dp, "declared_height_m": round(dh, 5), "expected": expected,
            "reference": ("%s_ref" % short) if reference and pile != "none" else "",
            "render_key": key})

    add("ref", "reference")
    # Poses: level at three heights, roll alone, pitch 5-30 with roll -5/0/+5 aimed at H/3.
    add("level_h050", "pose", aim_z=0.5 * h)
    add("level_h100", "pose", aim_z=1.0 * h)
    for roll in (-5, 5):
        add("level_roll%+d" % roll, "pose", roll=roll)
    for pitch in (5, 10, 20, 30):
        for roll in (-5, 0, 5):
            add("pitch%02d_roll%+d" % (pitch, roll), "pose", pitch=pitch, roll=roll, aim_z=h / 3)
    # Appearance at the reference pose.
    for g in ("dark", "light", "multi"):
        add("colour_" + g, "colour", grains=g)
    add("texture_granite", "texture", grains="textured")
    add("sidelight_left", "side_light", light="side_left")
    add("sidelight_right", "side_light", light="side_right")
    add("backdrop_checker", "background", backdrop="checker")
    add("backdrop_mottled", "background", backdrop="mottled")
    # The reference render, degraded afterwards.
    for q in (60, 75, 90):
        add("jpeg%d" % q, "jpeg", post="jpeg%d" % q)
    add("half", "resolution", post="half", size=(960, 540))
    add("double", "resolution", size=(3840, 2160))
    add("blur1_noise2", "blur_noise", post="blur1.0_noise0.02")
    add("blur2_noise5", "blur_noise", post="blur2.5_noise0.05")
    # Several nuisances at once, on pitched and rolled cameras.
    add("combo_p10r3_side_jpeg75", "combined", pitch=10, roll=3, aim_z=h / 3, light="side_left",
        post="jpeg75")
    add("combo_p20rm3_mottled_blur", "combined", pitch=20, roll=-3, aim_z=h / 3,
        backdrop="mottled", post="blur1.0_noise0.02")
    # Contradicted sidecars: declared level (aim (0,0,0)) but taken pitched 12 deg; declared
    # pitched 10 deg (aimed at H/3) but taken level at plate height.
    add("contra_decl0_took12", "contradicted", pitch=12, aim_z=h / 3, declared=(0.0, 0.0),
        expected="refuse:camera_mismatch")
    add("contra_decl10_took0", "contradicted", declared=(10.0, h / 3),
        expected="refuse:camera_mismatch")
    # Planted failures and the box that must not be one.
    add("funnel_gap3mm", "funnel", extra="funnel:%.5f" % (h + 0.003),
        expected="refuse:foreign_object")
    add("funnel_gap6mm_p10", "funnel", pitch=10, aim_z=h / 3, extra="funnel:%.5f" % (h + 0.006),
        expected="refuse:foreign_object")
    # The frame moved left so that its left border cuts the pile 0.65 R left of the axis.
    add("cut_left", "border_cut", aim_x=-0.65 * r + F / 2, expected="refuse:cut_by_border")
    # A wider field (the pile small in frame) with a box on the bench behind the plate, cut by
    # the image's right border: the pile is whole, so it is measured.
    add("edge_box", "edge_box", field=1.6 * F, extra="box", expected="measure")
    add("overexposed", "exposure", light="overexposed", expected="refuse:exposure")
    return rows


def empty_rows(h, r, rmax):
    # The empty plate framed as the quick twin pile was (its geometry), level and pitched.
    rows = []
    for id_, pitch, aim in (("empty_level", 0, 0.0), ("empty_p10", 10, h / 3)):
        rows.extend(r_ for r_ in photo_rows_empty(id_, pitch, aim, h, r, rmax))
    return rows


def photo_rows_empty(id_, pitch, aim, h, r, rmax):
    L, F = 12.0 * r, max(3.2 * r, 2.2 * rmax)
    cam = render.pose_camera(pitch, 0, aim, L, F)
    return [{"id": id_, "pile": "none", "nuisance": "empty_plate", "pitch_deg": pitch,
             "roll_deg": 0, "aim_x_m": 0.0, "aim_z_m": round(aim, 5), "distance_m": round(L, 5),
             "camera_height_m": round(cam.position[2], 5), "field_width_m": round(F, 5),
             "width_px": 1920, "height_px": 1080, "grains": "", "light": "even",
             "backdrop": "plain", "extra": "", "post": "png", "sidecar": "truthful",
             "declared_pitch_deg": pitch, "declared_height_m": round(cam.position[2], 5),
             "expected": "refuse:no_pile", "reference": "",
             "render_key": "none|%s|%s|%s|%s" % (pitch, aim, L, F)}]


def cmd_manifest(a):
    rows = []
    for p in PILES:
        if not os.path.exists(os.path.join(PILES_DIR, p + ".csv")):
            print("manifest: WARNING: no pile %s (%s.csv); its photos are left out" % (p, p))
            continue
        h, r, rmax = geometry(p)
        rows.extend(photo_rows(p, SHORT[p], h, r, rmax))
        if p == "twin_quick" or (p == "liggghts_pour" and not any(x["pile"] == "none" for x in rows)
                                 and not os.path.exists(os.path.join(PILES_DIR, "twin_quick.csv"))):
            rows.extend(empty_rows(h, r, rmax))
    with open(a.out, "w", newline="") as f:
        w = csv.DictWriter(f, FIELDS, lineterminator="\n")
        w.writeheader()
        for row in rows:
            w.writerow(row)
    print("manifest: %d photos -> %s" % (len(rows), a.out))


# ---------------------------------------------------------------------------------------------

def scene_for(row, grains):
    cam = render.pose_camera(float(row["pitch_deg"]), float(row["roll_deg"]), float(row["aim_z_m"]),
                             float(row["distance_m"]), float(row["field_width_m"]),
                             int(row["width_px"]), int(row["height_px"]),
                             aim_x=float(row["aim_x_m"]))
    extras = []
    ex = row["extra"]
    if ex.startswith("funnel:"):
        extras.append(render.funnel_pov(float(ex.split(":")[1])))
    elif ex == "box":
        # On the bench behind the plate, its left face 40 mm inside the right border (at the
        # box's depth), reaching beyond the border and above the image.
        L, F = float(row["distance_m"]), float(row["field_width_m"])
        y0, y1 = 0.30, 0.45
        half_at = 0.5 * F * (L * math.cos(math.radians(float(row["pitch_deg"]))) + y0) / L
        extras.append(render.box_pov(half_at - 0.04, half_at + 0.25, y0, y1, 0.35))
    look = {"grains": row["grains"] or "rock", "light": row["light"], "backdrop": row["backdrop"],
            "seed": 1}
    return cam, render.scene_pov(cam, look, grains, extras)


def declared_camera(row):
    """The camera the sidecar declares: the true one, or for a contradicted sidecar the declared
    pitch aimed as that pose's rule aims it (level: at (0, 0, 0); pitched: at H/3)."""
    true_cam = render.pose_camera(float(row["pitch_deg"]), float(row["roll_deg"]),
                                  float(row["aim_z_m"]), float(row["distance_m"]),
                                  float(row["field_width_m"]), int(row["width_px"]),
                                  int(row["height_px"]), aim_x=float(row["aim_x_m"]))
    if row["sidecar"] == "truthful":
        return true_cam
    dp = float(row["declared_pitch_deg"])
    # Aim: the declared camera's height is L sin(dp) + aim_z.
    aim = float(row["declared_height_m"]) - float(row["distance_m"]) * math.sin(math.radians(dp))
    return render.pose_camera(dp, 0.0, aim, float(row["distance_m"]), float(row["field_width_m"]),
                              int(row["width_px"]), int(row["height_px"]))


def post_process(src, row, dst_base):
    """Applies the row's post-processing to the rendered PNG; returns the photo's path."""
    post = row["post"]
    if post == "png":
        dst = dst_base + ".png"
        os.replace(src, dst) if src != dst else None
        return dst
    if post.startswith("jpeg"):
        dst = dst_base + ".jpg"
        render.convert([src, "-quality", post[4:], "-sampling-factor", "4:2:0", dst])
    elif post == "half":
        dst = dst_base + ".png"
        render.convert([src, "-filter", "Box", "-resize", "50%", dst])
    elif post.startswith("blur"):
        b, n = post[4:].split("_noise")
        dst = dst_base + ".png"
        render.convert([src, "-gaussian-blur", "0x" + b, "-seed", "51",
                        "-attenuate", "%.4f" % (float(n) / 0.1), "+noise", "Gaussian", dst])
    else:
        raise ValueError("unknown post " + post)
    return dst


def cmd_render(a):
    with open(a.manifest) as f:
        rows = list(csv.DictReader(f))
    if a.only:
        keep = set(a.only.split(","))
        rows = [r for r in rows if r["id"] in keep]
    os.makedirs(a.out, exist_ok=True)
    cache_dir = os.path.join(a.out, "renders")
    os.makedirs(cache_dir, exist_ok=True)
    # One render per distinct scene (render_key); the post-processed photos share it. Each
    # POV-Ray runs on one thread (its multithreaded antialiasing is not reproducible pixel for
    # pixel), and `--jobs` of them at once.
    by_key = {}
    for r in rows:
        by_key.setdefault(r["render_key"], []).append(r)
    piles = {p: render.read_pile(os.path.join(PILES_DIR, p + ".csv"))
             for p in {r["pile"] for r in rows if r["pile"] != "none"}}

    def one(n, group):
        row = group[0]
        grains, _ = piles.get(row["pile"], ([], ""))
        native = dict(row)
        if row["post"] == "half":
            native["width_px"], native["height_px"] = "1920", "1080"
        cam, pov = scene_for(native, grains)
        src = os.path.join(cache_dir, "r%03d.png" % n)
        done = all(os.path.exists(os.path.join(a.out, r["id"] + (".jpg" if r["post"].startswith("jpeg") else ".png")))
                   and os.path.exists(os.path.join(a.out, r["id"] + ".json")) for r in group)
        if done and not a.force:
            return None
        dt = render.povray(pov, src, cam.width_px, cam.height_px, aa=True, threads=a.threads)
        for r in group:
            tmp = src + "." + r["id"] + ".png"
            with open(src, "rb") as fi, open(tmp, "wb") as fo:
                fo.write(fi.read())
            photo = post_process(tmp, r, os.path.join(a.out, r["id"]))
            if os.path.exists(tmp):
                os.remove(tmp)
            dcam = declared_camera(r)
            render.write_sidecar(os.path.join(a.out, r["id"] + ".json"), dcam, {
                "made_by": "experiments/vision_nuisance/make_set.py (POV-Ray)",
                "photo": os.path.basename(photo), "pile": r["pile"], "nuisance": r["nuisance"],
                "sidecar": r["sidecar"], "expected": r["expected"]})
        os.remove(src)
        print("render %3d/%d %-34s %5.1f s (%d photo%s)" % (n + 1, len(by_key), group[0]["id"], dt,
              len(group), "" if len(group) == 1 else "s"), flush=True)
        return dt

    t_all = time.time()
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        futures = [pool.submit(one, n, g) for n, g in enumerate(by_key.values())]
        times = [f.result() for f in futures]
    times = [t for t in times if t is not None]
    if times:
        print("rendered %d scenes in %.0f s (%d at once; POV-Ray %.0f s, mean %.1f s, max %.1f s)"
              % (len(times), time.time() - t_all, max(1, a.jobs), sum(times),
                 sum(times) / len(times), max(times)))


def cmd_check(a):
    worst, rows = render.camera_check(os.path.join(a.out, "camera_check"), print)
    with open(os.path.join(a.out, "camera_check.csv"), "w") as f:
        f.write("camera,x_m,y_m,z_m,u_projected,v_projected,u_centroid,v_centroid,error_px\n")
        for name, p, uv, g, err in rows:
            f.write("%s,%.6f,%.6f,%.6f,%.3f,%.3f,%.3f,%.3f,%.4f\n" % (name, *p, *uv, *g, err))
    ok = worst < 0.5
    print("camera check: %d spheres, worst %.3f px: %s" % (len(rows), worst,
          "PASS (< 0.5 px)" if ok else "FAIL (>= 0.5 px)"))
    return 0 if ok else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("manifest")
    m.add_argument("--out", default=os.path.join(HERE, "manifest.csv"))
    r = sub.add_parser("render")
    r.add_argument("--manifest", default=os.path.join(HERE, "manifest.csv"))
    r.add_argument("--out", required=True)
    r.add_argument("--only", default="")
    r.add_argument("--threads", type=int, default=1, help="POV-Ray threads per render")
    r.add_argument("--jobs", type=int, default=2, help="renders at once")
    r.add_argument("--force", action="store_true")
    c = sub.add_parser("check")
    c.add_argument("--out", required=True)
    a = ap.parse_args()
    if a.cmd == "manifest":
        cmd_manifest(a)
    elif a.cmd == "render":
        cmd_render(a)
    else:
        sys.exit(cmd_check(a))


if __name__ == "__main__":
    main()
