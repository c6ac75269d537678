#!/usr/bin/env python3
"""evaluate.py: measures every photo of the nuisance set with a reposetwin binary and prints
issue 51's acceptance table.

  evaluate.py --photos DIR --label NAME [--bin BIN] [--manifest manifest.csv] [--out-dir DIR]

Each photo is measured alone, through its own sidecar:
  BIN measure PHOTO --camera SIDECAR --json --no-overlay
with its wall time. Outcomes:
  - measured: exit 0 and a JSON record with theta_deg (and no "refused" object);
  - refused:<check>: a non-zero exit with, on stdout, {"refused": {"check", "measured", "limit",
    "message"}} (the rewritten vision); a non-zero exit without that object (today's vision
    prints an error on stderr) is refused:unknown, its message kept;
  - error: the binary could not be run, or timed out.
A binary that rejects the sidecar's "plate" key (a sidecar field added with the rewrite) is given
the same sidecar without it; that is probed once on the reference photo and recorded.

Writes OUT_DIR/LABEL.csv (a row per photo) and OUT_DIR/LABEL.md (the tables and provenance).
Standard library only.
"""
import argparse
import csv
import datetime
import hashlib
import json
import math
import os
import re
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
DEFAULT_BIN = os.path.join(ROOT, "build", "apps", "reposetwin", "reposetwin")
COLUMNS = ["id", "pile", "nuisance", "sidecar", "expected", "reference", "outcome", "exit_code",
           "theta_deg", "sigma_theta_deg", "H_mm", "D_mm", "flank_deg", "check",
           "check_measured", "check_limit", "message", "warnings", "wall_s", "ref_theta_deg",
           "dtheta_deg", "within_1deg", "within_2deg", "ci95_covers_ref", "as_expected",
           "elevation_above_top_deg"]


def sidecar_of(photos, row):
    return os.path.join(photos, row["id"] + ".json")


def photo_path(photos, row):
    for ext in (".png", ".jpg"):
        p = os.path.join(photos, row["id"] + ext)
        if os.path.exists(p):
            return p
    return None


def strip_plate(sidecar, dst_dir):
    with open(sidecar) as f:
        j = json.load(f)
    j.pop("plate", None)
    os.makedirs(dst_dir, exist_ok=True)
    dst = os.path.join(dst_dir, os.path.basename(sidecar))
    with open(dst, "w") as f:
        json.dump(j, f, indent=2, sort_keys=True)
    return dst


def run_measure(binary, photo, sidecar, timeout):
    cmd = ["nice", "-n", "19", binary, "measure", photo, "--camera", sidecar, "--json",
           "--no-overlay"]
    t0 = time.time()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                           env=dict(os.environ, OMP_NUM_THREADS="1"))
    except subprocess.TimeoutExpired:
        return {"outcome": "error", "exit_code": "", "message": "timed out after %d s" % timeout,
                "wall_s": time.time() - t0}
    except OSError as e:
        return {"outcome": "error", "exit_code": "", "message": str(e), "wall_s": time.time() - t0}
    wall = time.time() - t0
    res = {"exit_code": r.returncode, "wall_s": wall}
    j = None
    try:
        j = json.loads(r.stdout) if r.stdout.strip() else None
    except ValueError:
        j = None
    if isinstance(j, dict) and isinstance(j.get("refused"), dict):
        ref = j["refused"]
        res.update(outcome="refused:%s" % ref.get("check", "unknown"), check=ref.get("check", ""),
                   check_measured=ref.get("measured", ""), check_limit=ref.get("limit", ""),
                   message=str(ref.get("message", "")))
        return res
    if r.returncode == 0 and isinstance(j, dict) and j.get("theta_deg") is not None:
        res.update(outcome="measured", theta_deg=j["theta_deg"],
                   sigma_theta_deg=j.get("sigma_theta_deg"),
                   H_mm=1e3 * j["H_m"] if j.get("H_m") is not None else "",
                   D_mm=1e3 * j["D_m"] if j.get("D_m") is not None else "",
                   flank_deg=j.get("flank_deg", ""),
                   warnings=" | ".join(j.get("warnings", [])))
        return res
    msg = (r.stderr.strip().splitlines() or [r.stdout.strip()[:300]] or [""])
    res.update(outcome="refused:unknown" if r.returncode != 0 else "error", check="unknown",
               message=" ".join(msg)[-600:])
    return res


def message_kind(msg):
    """A refusal message without its photo path and numbers, cut at its first parenthesis or
    colon after the first clause: the kind of refusal."""
    m = re.sub(r"^reposetwin: error: ", "", msg or "")
    m = re.sub(r"^\S+\.(png|jpg|json): ", "", m)
    m = re.sub(r"[-+]?\d+(\.\d+)?", "#", m)
    for stop in (" (", "; "):
        if stop in m:
            m = m[:m.index(stop)]
    return m[:110]


def fmt(v, p=3):
    if v is None or v == "":
        return ""
    if isinstance(v, float):
        return ("%%.%df" % p) % v
    return str(v)


def frac(k, n):
    return "%d/%d (%.0f%%)" % (k, n, 100.0 * k / n) if n else "0/0"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=DEFAULT_BIN)
    ap.add_argument("--manifest", default=os.path.join(HERE, "manifest.csv"))
    ap.add_argument("--photos", required=True)
    ap.add_argument("--label", required=True)
    ap.add_argument("--out-dir", default=os.path.join(ROOT, "results", "vision_nuisance"))
    ap.add_argument("--timeout", type=int, default=300)
    ap.add_argument("--command", default="", help="the command line to record as provenance")
    ap.add_argument("--note", action="append", default=[], help="a line for the provenance")
    a = ap.parse_args()
    if not os.access(a.bin, os.X_OK):
        sys.exit("evaluate.py: %s: no such executable" % a.bin)
    with open(a.manifest) as f:
        rows = list(csv.DictReader(f))
    version = subprocess.run([a.bin, "--version"], capture_output=True, text=True).stdout.strip()
    with open(a.bin, "rb") as f:
        bin_sha = hashlib.sha256(f.read()).hexdigest()[:16]

    # Does this binary read the "plate" key of the sidecars? Probe on the first reference photo.
    strip = False
    probe = next(r for r in rows if r["nuisance"] == "reference")
    pp = photo_path(a.photos, probe)
    if pp is None:
        sys.exit("evaluate.py: %s: no photo %s (render the set first)" % (a.photos, probe["id"]))
    pr = run_measure(a.bin, pp, os.path.join(a.photos, probe["id"] + ".json"), a.timeout)
    if '"plate"' in pr.get("message", "") and "not a sidecar field" in pr.get("message", ""):
        strip = True
    plate_note = ("stripped: this binary refuses the sidecar key \"plate\" (%s); every sidecar was "
                  "given without it" % pr["message"][:200]) if strip else "kept"
    print("sidecar \"plate\" key: " + plate_note, flush=True)

    results = {}
    t_all = time.time()
    for n, row in enumerate(rows):
        photo = photo_path(a.photos, row)
        sidecar = os.path.join(a.photos, row["id"] + ".json")
        if photo is None or not os.path.exists(sidecar):
            res = {"outcome": "error", "message": "photo or sidecar missing", "wall_s": 0.0}
        else:
            if strip:
                sidecar = strip_plate(sidecar, os.path.join(a.photos, "sidecars_without_plate"))
            res = run_measure(a.bin, photo, sidecar, a.timeout)
        results[row["id"]] = res
        print("%3d/%d %-36s %-22s %s" % (n + 1, len(rows), row["id"], res["outcome"],
              fmt(res.get("theta_deg"), 2) or res.get("message", "")[:90]), flush=True)
    wall_all = time.time() - t_all

    out_rows = []
    for row in rows:
        res = results[row["id"]]
        ref = results.get(row["reference"]) if row["reference"] else None
        o = {k: "" for k in COLUMNS}
        o.update({k: row[k] for k in ("id", "pile", "nuisance", "sidecar", "expected", "reference")})
        for k in ("outcome", "exit_code", "theta_deg", "sigma_theta_deg", "H_mm", "D_mm",
                  "flank_deg", "check", "check_measured", "check_limit", "message", "warnings",
                  "wall_s"):
            if res.get(k) is not None:
                o[k] = res.get(k)
        if ref and ref.get("outcome") == "measured":
            o["ref_theta_deg"] = ref["theta_deg"]
        if res.get("outcome") == "measured" and o["ref_theta_deg"] != "":
            d = res["theta_deg"] - o["ref_theta_deg"]
            o["dtheta_deg"] = d
            o["within_1deg"] = int(abs(d) <= 1.0)
            o["within_2deg"] = int(abs(d) <= 2.0)
            s = res.get("sigma_theta_deg")
            o["ci95_covers_ref"] = int(s is not None and abs(d) <= 1.96 * s)
        # The camera's elevation above the pile's top, seen from the axis (the plate's top at
        # z = 0, the axis at x = y = 0: make_set.py), with the reference photo's H: a cone's apex
        # is on its outline only while this is below the cone's angle.
        if ref and ref.get("outcome") == "measured" and os.path.exists(sidecar_of(a.photos, row)):
            with open(sidecar_of(a.photos, row)) as f:
                pos = json.load(f)["camera"]["extrinsics"]["position"]
            o["elevation_above_top_deg"] = math.degrees(math.atan2(
                pos[2] - 1e-3 * ref["H_mm"], math.hypot(pos[0], pos[1])))
        exp = row["expected"]
        want = "measured" if exp == "measure" else "refused:" + exp.split(":", 1)[1]
        o["as_expected"] = int(res.get("outcome") == want)
        out_rows.append(o)

    os.makedirs(a.out_dir, exist_ok=True)
    csv_path = os.path.join(a.out_dir, a.label + ".csv")
    with open(csv_path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(COLUMNS)
        for o in out_rows:
            w.writerow([fmt(o[k]) for k in COLUMNS])

    # ---- the tables
    pile_photos = [o for o in out_rows if o["expected"] == "measure" and o["sidecar"] == "truthful"
                   and o["nuisance"] != "reference"]
    refs = [o for o in out_rows if o["nuisance"] == "reference"]
    planted = [o for o in out_rows if o["expected"].startswith("refuse:")]
    N = len(pile_photos)
    measured = [o for o in pile_photos if o["outcome"] == "measured"]
    w1 = sum(1 for o in pile_photos if o["within_1deg"] == 1)
    w2 = sum(1 for o in pile_photos if o["within_2deg"] == 1)
    cov = sum(1 for o in pile_photos if o["ci95_covers_ref"] == 1)
    right = sum(1 for o in planted if o["as_expected"] == 1)
    any_ref = sum(1 for o in planted if o["outcome"].startswith("refused"))
    lines = []
    P = lines.append
    P("| acceptance (issue 51) | result | required | holds |")
    P("|---|---|---|---|")
    P("| reference photos measured | %s | all | %s |" % (frac(sum(o["outcome"] == "measured" for o in refs), len(refs)),
      "yes" if all(o["outcome"] == "measured" for o in refs) else "no"))
    P("| truthful-camera pile photos measured | %s | all | %s |" % (frac(len(measured), N), "yes" if len(measured) == N else "no"))
    P("| within 1.0 deg of the pile's reference | %s | >= 95%% | %s |" % (frac(w1, N), "yes" if N and w1 >= 0.95 * N else "no"))
    P("| within 2.0 deg of the pile's reference | %s | all | %s |" % (frac(w2, N), "yes" if w2 == N else "no"))
    P("| 95%% interval (theta +- 1.96 sigma) covers the reference | %s | >= 90%% | %s |" % (frac(cov, N), "yes" if N and cov >= 0.9 * N else "no"))
    P("| planted failures refused with the right check | %s | all | %s |" % (frac(right, len(planted)), "yes" if right == len(planted) else "no"))
    P("| planted failures refused at all (any check) | %s | | |" % frac(any_ref, len(planted)))
    P("")
    # A cone's apex is on its outline only while the camera stands below the cone's slope seen
    # from the axis: from higher up the flanks face the camera and H is not on the silhouette, so
    # no silhouette reading can give it (vision refuses such photos as view_too_steep). The rule
    # is geometry, fixed before reading: the camera's elevation above the pile's top (the
    # reference photo's H) against the reference photo's angle.
    seen = [o for o in pile_photos if o["elevation_above_top_deg"] == "" or
            o["ref_theta_deg"] == "" or o["elevation_above_top_deg"] < o["ref_theta_deg"]]
    hidden = [o for o in pile_photos if o not in seen]
    Ns = len(seen)
    ms = sum(1 for o in seen if o["outcome"] == "measured")
    w1s = sum(1 for o in seen if o["within_1deg"] == 1)
    w2s = sum(1 for o in seen if o["within_2deg"] == 1)
    covs = sum(1 for o in seen if o["ci95_covers_ref"] == 1)
    P("The same rows over the truthful pile photos whose camera stands below the pile's slope "
      "(elevation above the pile's top < the reference angle, so the apex is on the silhouette): "
      "%d of %d; the other %d (%s) show no apex on their outline, and %d of them were refused "
      "as view_too_steep." % (Ns, N, len(hidden), ", ".join(o["id"] for o in hidden) or "none",
                              sum(1 for o in hidden if o["outcome"] == "refused:view_too_steep")))
    P("")
    P("| where the apex is on the silhouette | result | required | holds |")
    P("|---|---|---|---|")
    P("| measured | %s | all | %s |" % (frac(ms, Ns), "yes" if ms == Ns else "no"))
    P("| within 1.0 deg | %s | >= 95%% | %s |" % (frac(w1s, Ns), "yes" if Ns and w1s >= 0.95 * Ns else "no"))
    P("| within 2.0 deg | %s | all | %s |" % (frac(w2s, Ns), "yes" if w2s == Ns else "no"))
    P("| 95%% interval covers | %s | >= 90%% | %s |" % (frac(covs, Ns), "yes" if Ns and covs >= 0.9 * Ns else "no"))
    P("")
    P("Denominators are all photos of the group: a photo not measured counts as outside 1 and 2 deg "
      "and as not covered; a pile whose reference photo is not measured has no reference value, so "
      "all its photos count as outside.")
    P("")
    P("Per pile: the reference photo's reading, and the spread of the readings of the pile's "
      "other photos expected measured that were measured (informative: it needs no reference).")
    P("")
    P("| pile | reference theta (deg) | H (mm) | D (mm) | sigma (deg) | others measured | their theta min / median / max (deg) |")
    P("|---|---|---|---|---|---|---|")
    for o in refs:
        th = sorted(x["theta_deg"] for x in pile_photos if x["pile"] == o["pile"] and x["outcome"] == "measured")
        n_p = sum(1 for x in pile_photos if x["pile"] == o["pile"])
        P("| %s | %s | %s | %s | %s | %d/%d | %s |" % (o["pile"], fmt(o["theta_deg"], 2) or o["outcome"],
          fmt(o["H_mm"], 1), fmt(o["D_mm"], 1), fmt(o["sigma_theta_deg"], 2), len(th), n_p,
          "%.2f / %.2f / %.2f" % (th[0], statistics.median(th), th[-1]) if th else ""))
    P("")
    P("| nuisance | photos | measured | within 1 deg | within 2 deg | 95% covers | median abs dtheta (deg) | max abs dtheta (deg) | as expected |")
    P("|---|---|---|---|---|---|---|---|---|")
    order = []
    for o in out_rows:
        if o["nuisance"] not in order:
            order.append(o["nuisance"])
    for nu in order:
        g = [o for o in out_rows if o["nuisance"] == nu]
        ds = [abs(o["dtheta_deg"]) for o in g if o["dtheta_deg"] != ""]
        P("| %s | %d | %d | %d | %d | %d | %s | %s | %d |" % (
            nu, len(g), sum(o["outcome"] == "measured" for o in g),
            sum(o["within_1deg"] == 1 for o in g), sum(o["within_2deg"] == 1 for o in g),
            sum(o["ci95_covers_ref"] == 1 for o in g),
            "%.2f" % statistics.median(ds) if ds else "", "%.2f" % max(ds) if ds else "",
            sum(o["as_expected"] == 1 for o in g)))
    P("")
    P("| outcome | photos |")
    P("|---|---|")
    counts = {}
    for o in out_rows:
        counts[o["outcome"]] = counts.get(o["outcome"], 0) + 1
    for k in sorted(counts):
        P("| %s | %d |" % (k, counts[k]))
    P("")
    P("Refusal messages by kind (the path and the numbers left out), with the nuisances they met:")
    P("")
    P("| message | photos | nuisances |")
    P("|---|---|---|")
    kinds = {}
    for o in out_rows:
        if o["outcome"].startswith("refused") or o["outcome"] == "error":
            kinds.setdefault(message_kind(o["message"]), []).append(o["nuisance"])
    for k, v in sorted(kinds.items(), key=lambda kv: -len(kv[1])):
        c = {}
        for x in v:
            c[x] = c.get(x, 0) + 1
        P("| %s | %d | %s |" % (k.replace("|", "/"), len(v),
          ", ".join("%s %d" % (x, n) for x, n in sorted(c.items(), key=lambda t: -t[1]))))
    P("")
    P("Planted failures:")
    P("")
    P("| photo | expected | outcome | message |")
    P("|---|---|---|---|")
    for o in planted:
        msg = (re.sub(r"^reposetwin: error: \S+\.(png|jpg): ", "", o["message"]) or ("theta %.2f deg, H %.1f mm, D %.1f mm" % (o["theta_deg"], o["H_mm"], o["D_mm"])
               if o["outcome"] == "measured" else "")).replace("|", "/")
        P("| %s | %s | %s | %s |" % (o["id"], o["expected"], o["outcome"], msg[:160]))
    walls = [float(o["wall_s"]) for o in out_rows if o["wall_s"] != ""]
    P("")
    P("Wall time per photo: median %.2f s, max %.2f s; all %d photos %.0f s (nice 19, shared cores)."
      % (statistics.median(walls), max(walls), len(walls), wall_all))
    table = "\n".join(lines)
    print()
    print(table)

    with open(a.manifest, "rb") as f:
        man_sha = hashlib.sha256(f.read()).hexdigest()[:16]
    git = subprocess.run(["git", "-C", ROOT, "log", "-1", "--format=%h %cI", "--",
                          "experiments/vision_nuisance"], capture_output=True, text=True).stdout.strip()
    prov = ["# Vision nuisance set: %s" % a.label, "",
            "- binary: `%s`, `--version`: %s, sha256 %s..." % (a.bin, version or "(none)", bin_sha),
            "- measured: %s UTC" % datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"),
            "- command: `%s`" % (a.command or " ".join([sys.argv[0]] + sys.argv[1:])),
            "- per photo: `BIN measure PHOTO --camera SIDECAR --json --no-overlay` (nice 19)",
            "- manifest: experiments/vision_nuisance/manifest.csv (sha256 %s...), %d photos; "
            "set scripts at %s" % (man_sha, len(rows), git or "(uncommitted)"),
            "- sidecar \"plate\" key: %s" % plate_note,
            ] + ["- " + n for n in a.note] + [
            "- rows: results/vision_nuisance/%s.csv" % a.label, "", table, ""]
    with open(os.path.join(a.out_dir, a.label + ".md"), "w") as f:
        f.write("\n".join(prov))
    print("\nwrote %s and %s.md" % (csv_path, os.path.join(a.out_dir, a.label)))


if __name__ == "__main__":
    main()
