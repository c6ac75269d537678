#!/usr/bin/env python3
"""render.py: POV-Ray photographs of the nuisance set's piles, through the project's camera model.

Design note. The photos must be independent of render/ (another renderer, other lights, other
materials) and yet taken through exactly the camera the sidecar declares, or the set would test
the renderer rather than vision. So this file implements the project's pinhole model again from
its definition in camera/camera.hpp (perspective, focal_length_mm / sensor_width_mm * width_px
pixels of focal length, square pixels, principal point ((W-1)/2, (H-1)/2), world z up, the camera
frame's x right, y down, z forward, built from position, look_at and up), and hands POV-Ray that
camera as explicit location/direction/right/up vectors in world coordinates (no look_at, no sky):
POV-Ray then traces the ray direction + s * right + t * up for the screen point (s, t) and no
handedness convention enters; `check` renders small glowing spheres at known points and compares
their pixel centroids with this module's projection.

World: SI metres, z up, the plate's top face at z = 0 (a 0.5 m square, 10 mm thick, edges along
x and y, on a bench), the pile axis on the z axis, a backdrop plane behind the pile.

Standard library only; POV-Ray (Debian `povray`) renders; ImageMagick (Debian `imagemagick`,
/usr/bin/convert) does JPEG, resizing, blur and noise.
"""
import json
import math
import os
import random
import shutil
import subprocess
import time

PLATE_SIZE_M = 0.5
PLATE_THICKNESS_M = 0.01
SENSOR_WIDTH_MM = 36.0
BACKDROP_Y_M = 0.55          # the backdrop plane y = const, behind the pile
BENCH_FRONT_Y_M = -0.40      # the bench's front edge (the camera stands in front of it)
CONVERT = "/usr/bin/convert"


# ---------------------------------------------------------------------------------------------
# The project's camera model (camera/camera.hpp, camera.cpp), restated

def _sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def _add(a, b):
    return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]


def _mul(a, s):
    return [a[0] * s, a[1] * s, a[2] * s]


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _unit(a):
    n = math.sqrt(_dot(a, a))
    return [a[0] / n, a[1] / n, a[2] / n]


class Camera:
    """A perspective pinhole camera as camera::Camera: intrinsics and extrinsics."""

    def __init__(self, position, look_at, up, focal_length_mm, width_px, height_px,
                 sensor_width_mm=SENSOR_WIDTH_MM, cx_px=None, cy_px=None, name="side"):
        self.position = list(position)
        self.look_at = list(look_at)
        self.up = list(up)
        self.focal_length_mm = focal_length_mm
        self.sensor_width_mm = sensor_width_mm
        self.width_px = int(width_px)
        self.height_px = int(height_px)
        self.cx_px = 0.5 * (self.width_px - 1) if cx_px is None else cx_px
        self.cy_px = 0.5 * (self.height_px - 1) if cy_px is None else cy_px
        self.name = name

    def focal_px(self):
        return self.focal_length_mm / self.sensor_width_mm * self.width_px

    def axes(self):
        """The camera's x (right), y (down), z (forward) axes in world coordinates."""
        z = _unit(_sub(self.look_at, self.position))
        x = _unit(_cross(z, self.up))
        y = _cross(z, x)
        return x, y, z

    def project(self, p):
        x, y, z = self.axes()
        d = _sub(p, self.position)
        pc = (_dot(x, d), _dot(y, d), _dot(z, d))
        if pc[2] <= 0:
            return None
        f = self.focal_px()
        return (self.cx_px + f * pc[0] / pc[2], self.cy_px + f * pc[1] / pc[2])

    def scaled(self, factor):
        """The same camera with `factor` times as many pixels per side (same lens and sensor)."""
        w, h = int(round(self.width_px * factor)), int(round(self.height_px * factor))
        # A resampled image's pixel centres: u' = (u + 0.5) * factor - 0.5.
        return Camera(self.position, self.look_at, self.up, self.focal_length_mm, w, h,
                      self.sensor_width_mm, (self.cx_px + 0.5) * factor - 0.5,
                      (self.cy_px + 0.5) * factor - 0.5, self.name)

    def to_json(self):
        return {"name": self.name, "projection": "perspective",
                "intrinsics": {"width_px": self.width_px, "height_px": self.height_px,
                               "focal_length_mm": self.focal_length_mm,
                               "sensor_width_mm": self.sensor_width_mm,
                               "k1": 0.0, "k2": 0.0, "cx_px": self.cx_px, "cy_px": self.cy_px},
                "extrinsics": {"position": self.position, "look_at": self.look_at,
                               "up": self.up}}

    def pov(self):
        """POV-Ray's camera for this one: explicit world vectors. POV-Ray traces the ray
        direction + s * right + t * up through screen point s = (u + 0.5) / W - 0.5,
        t = 0.5 - (v + 0.5) / H; with right = W/f x, up = -H/f y and the principal point's offset
        folded into direction, that ray is the pinhole's ray through pixel (u, v)."""
        x, y, z = self.axes()
        f = self.focal_px()
        w, h = self.width_px, self.height_px
        direction = _add(z, _add(_mul(x, (0.5 * (w - 1) - self.cx_px) / f),
                                 _mul(y, (0.5 * (h - 1) - self.cy_px) / f)))
        right = _mul(x, w / f)
        up = _mul(y, -h / f)
        v = lambda a: "<%.9f, %.9f, %.9f>" % tuple(a)
        return ("camera {\n  perspective\n  location %s\n  direction %s\n  right %s\n  up %s\n}\n"
                % (v(self.position), v(direction), v(right), v(up)))


def pose_camera(pitch_deg, roll_deg, aim_z, distance_m, field_width_m, width_px=1920,
                height_px=1080, azimuth_deg=0.0, aim_x=0.0, name="side"):
    """A lab camera aimed at the point (aim_x, 0, aim_z) on the pile from `distance_m`, looking
    down by `pitch_deg`, from azimuth `azimuth_deg` (0 = from -y, as camera::side_view), rolled
    by `roll_deg` about its viewing direction (positive: the camera turned clockwise as seen from
    behind it, so the scene appears turned anticlockwise). The focal length makes a field
    `field_width_m` wide at the aim point fill the image width."""
    p, a, r = (math.radians(t) for t in (pitch_deg, azimuth_deg, roll_deg))
    back = [math.sin(a) * math.cos(p), -math.cos(a) * math.cos(p), math.sin(p)]  # aim -> camera
    aim = [aim_x, 0.0, aim_z]
    pos = _add(aim, _mul(back, distance_m))
    fwd = _mul(back, -1.0)
    x0 = _unit(_cross(fwd, [0.0, 0.0, 1.0]))
    up0 = _cross(x0, fwd)  # world up projected perpendicular to the view
    up = _add(_mul(up0, math.cos(r)), _mul(x0, math.sin(r)))
    f_mm = distance_m / field_width_m * SENSOR_WIDTH_MM
    return Camera(pos, aim, up, f_mm, width_px, height_px, name=name)


# ---------------------------------------------------------------------------------------------
# Scene

def read_pile(path):
    grains, prov = [], ""
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                prov = line[1:].strip()
            elif line[0].isdigit() or line[0] in "-.":
                grains.append(tuple(float(v) for v in line.split(",")))
    return grains, prov


def pile_size(grains):
    """(H, R): the top of the highest grain and the 95th percentile of the grains' outer radius."""
    h = max(z + r for _, _, z, r in grains)
    rad = sorted(math.hypot(x, y) + r for x, y, _, r in grains)
    return h, rad[int(0.95 * (len(rad) - 1))]


PALETTES = {
    # (base rgb, per-grain spread) for the grain colour modes.
    "rock": [((0.52, 0.47, 0.40), 0.08), ((0.45, 0.44, 0.42), 0.06), ((0.58, 0.52, 0.43), 0.06)],
    "dark": [((0.16, 0.16, 0.17), 0.03), ((0.20, 0.18, 0.16), 0.03)],
    "light": [((0.78, 0.75, 0.68), 0.04), ((0.72, 0.70, 0.66), 0.04)],
    "multi": [((0.70, 0.25, 0.18), 0.08), ((0.25, 0.45, 0.25), 0.06), ((0.85, 0.72, 0.35), 0.06),
              ((0.15, 0.15, 0.18), 0.04), ((0.85, 0.84, 0.80), 0.04), ((0.45, 0.30, 0.22), 0.05)],
}


def grains_pov(grains, mode, seed):
    """The grains as POV-Ray spheres. `mode`: a palette name, or "textured" (granite pigment)."""
    rnd = random.Random(seed)
    out = []
    if mode == "textured":
        out.append("#declare T_grain = texture { pigment { granite scale 0.004 color_map {"
                   " [0.0 rgb <0.20,0.18,0.16>] [0.35 rgb <0.55,0.50,0.44>]"
                   " [0.6 rgb <0.80,0.78,0.72>] [1.0 rgb <0.35,0.30,0.26>] } }"
                   " normal { bumps 0.6 scale 0.0015 } finish { diffuse 0.8 specular 0.05 } }\n")
        for x, y, z, r in grains:
            out.append("sphere { <%.5f,%.5f,%.5f>, %.5f texture { T_grain translate <%.3f,%.3f,%.3f> } }\n"
                       % (x, y, z, r, rnd.random(), rnd.random(), rnd.random()))
        return "".join(out)
    palette = PALETTES[mode]
    for x, y, z, r in grains:
        (b, s) = rnd.choice(palette)
        k = rnd.gauss(0, 1)
        c = [min(1.0, max(0.0, b[i] + s * (k + 0.3 * rnd.gauss(0, 1)))) for i in range(3)]
        out.append("sphere { <%.5f,%.5f,%.5f>, %.5f pigment { rgb <%.3f,%.3f,%.3f> } "
                   "finish { F_grain } }\n" % (x, y, z, r, c[0], c[1], c[2]))
    return "".join(out)


def scene_pov(cam, look, grains, extras):
    """The whole scene: camera, lights, backdrop, bench, plate, grains and extras.
    look: dict with 'grains' (colour mode), 'light' ('even', 'side_left', 'side_right',
    'overexposed'), 'backdrop' ('plain', 'checker', 'mottled'), 'seed'."""
    s = ["#version 3.7;\nglobal_settings { assumed_gamma 1.0 max_trace_level 5 }\n",
         "#declare F_grain = finish { ambient 0.06 diffuse 0.85 specular 0.04 roughness 0.05 }\n",
         cam.pov()]
    cp = cam.position
    light = look.get("light", "even")
    gain = 6.0 if light == "overexposed" else 1.0
    if light in ("even", "overexposed"):
        # Two lights beside the camera and one above, shadows soft and faint: even light.
        for dx, dz, w in ((-0.8, 0.6, 0.45), (0.8, 0.6, 0.45), (0.0, 1.5, 0.35)):
            s.append("light_source { <%.3f,%.3f,%.3f> rgb %.3f area_light <0.3,0,0>, <0,0,0.3>, 3, 3"
                     " adaptive 0 }\n" % (cp[0] + dx, cp[1] - 0.2, max(cp[2], 0) + dz, w * gain))
        s.append("light_source { <0,-0.6,2.5> rgb %.3f shadowless }\n" % (0.25 * gain))
    else:
        sx = -1.0 if light == "side_left" else 1.0
        # A low lamp from the side: hard shadows across the plate and the pile's far flank dark.
        s.append("light_source { <%.3f,-0.25,0.28> rgb 1.15 }\n" % (1.6 * sx))
        s.append("light_source { <%.3f,%.3f,%.3f> rgb 0.12 shadowless }\n" % (cp[0], cp[1], cp[2] + 0.3))
    back = look.get("backdrop", "plain")
    if back == "plain":
        bp = "pigment { rgb <0.88,0.88,0.86> }"
    elif back == "checker":
        bp = ("pigment { checker rgb <0.85,0.2,0.15>, rgb <0.1,0.2,0.55> scale 0.045 }"
              " ")
    else:  # mottled: a busy cloth/poster-like pattern of many colours
        bp = ("pigment { bozo turbulence 0.6 scale 0.03 color_map { [0.0 rgb <0.9,0.85,0.3>]"
              " [0.25 rgb <0.2,0.5,0.3>] [0.5 rgb <0.8,0.8,0.8>] [0.75 rgb <0.3,0.2,0.2>]"
              " [1.0 rgb <0.2,0.3,0.7>] } }")
    s.append("plane { y, %.3f %s finish { ambient 0.15 diffuse 0.7 } }\n" % (BACKDROP_Y_M, bp))
    # The bench: its top under the plate, its front face towards the camera; a floor far below.
    s.append("box { <-2.0,%.3f,-0.9>, <2.0,%.3f,%.4f> pigment { rgb <0.42,0.33,0.24> }"
             " finish { ambient 0.1 diffuse 0.7 } }\n" % (BENCH_FRONT_Y_M, BACKDROP_Y_M, -PLATE_THICKNESS_M))
    s.append("plane { z, -0.9 pigment { rgb 0.3 } }\n")
    hp = PLATE_SIZE_M / 2
    s.append("box { <%.4f,%.4f,%.4f>, <%.4f,%.4f,0.0> pigment { rgb <0.50,0.51,0.53> }"
             " finish { ambient 0.08 diffuse 0.75 specular 0.15 roughness 0.02 } }\n"
             % (-hp, -hp, -PLATE_THICKNESS_M, hp, hp))
    if grains:
        s.append(grains_pov(grains, look.get("grains", "rock"), look.get("seed", 1)))
    s.extend(extras)
    return "".join(s)


def funnel_pov(outlet_z):
    """The paper's funnel (40 mm outlet, 190 mm top, 120 mm high), steel, hanging with its
    outlet's bottom rim `outlet_z` above the plate on the pile axis."""
    return ("difference { cone { <0,0,%.4f>, 0.022, <0,0,%.4f>, 0.097 }"
            " cone { <0,0,%.4f>, 0.020, <0,0,%.4f>, 0.095 }"
            " pigment { rgb <0.62,0.63,0.66> } finish { ambient 0.1 diffuse 0.6 specular 0.5 roughness 0.01 metallic } }\n"
            % (outlet_z, outlet_z + 0.12, outlet_z - 0.001, outlet_z + 0.121))


def box_pov(x0, x1, y0, y1, height):
    """A cardboard box standing on the bench."""
    return ("box { <%.4f,%.4f,%.4f>, <%.4f,%.4f,%.4f> pigment { rgb <0.55,0.42,0.28> }"
            " finish { ambient 0.1 diffuse 0.7 } }\n"
            % (x0, y0, -PLATE_THICKNESS_M, x1, y1, -PLATE_THICKNESS_M + height))


def povray(pov_text, out_png, width, height, aa=True, threads=1):
    """Renders a scene to a PNG; returns the wall time [s]."""
    pov_path = out_png[:-4] + ".pov"
    with open(pov_path, "w") as f:
        f.write(pov_text)
    cmd = ["nice", "-n", "19", "povray", "-D", "-V", "+I" + pov_path, "+O" + out_png, "+FN8",
           "+W%d" % width, "+H%d" % height, "+WT%d" % threads, "+Q9"]
    cmd += ["+A0.3", "+AM2", "+R2", "-J"] if aa else ["-A"]
    t0 = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0 or not os.path.exists(out_png):
        raise RuntimeError("povray failed on %s: %s" % (pov_path, r.stderr[-2000:]))
    os.remove(pov_path)
    return time.time() - t0


def convert(args):
    r = subprocess.run(["nice", "-n", "19", CONVERT] + args, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError("convert %s: %s" % (" ".join(args), r.stderr))


def write_sidecar(path, cam, provenance):
    j = {"camera": cam.to_json(), "view": "side",
         "image": {"width_px": cam.width_px, "height_px": cam.height_px},
         "plate": {"size_m": PLATE_SIZE_M, "thickness_m": PLATE_THICKNESS_M},
         "provenance": provenance}
    with open(path + ".tmp", "w") as f:
        json.dump(j, f, indent=2, sort_keys=True)
    os.replace(path + ".tmp", path)


# ---------------------------------------------------------------------------------------------
# The camera check: glowing spheres at known points, their centroids against the projection

def read_ppm_or_png_gray(path):
    """Greyscale values of an image via ImageMagick's PGM output: (w, h, bytes)."""
    r = subprocess.run([CONVERT, path, "-colorspace", "Gray", "-depth", "8", "pgm:-"],
                       capture_output=True)
    data = r.stdout
    # P5 <w> <h> <maxval> then one byte per pixel; '#' comments may sit between the tokens.
    tokens, i = [], 0
    while len(tokens) < 4:
        while data[i:i + 1].isspace():
            i += 1
        if data[i:i + 1] == b"#":
            i = data.index(b"\n", i) + 1
            continue
        j = i
        while not data[j:j + 1].isspace():
            j += 1
        tokens.append(data[i:j])
        i = j
    w, h = int(tokens[1]), int(tokens[2])
    return w, h, data[i + 1:i + 1 + w * h]


def centroids(path, expected, radius_px):
    """Intensity-weighted centroid of the bright blob near each expected pixel."""
    w, h, px = read_ppm_or_png_gray(path)
    out = []
    win = int(radius_px * 2.5) + 4
    for (u0, v0) in expected:
        su = sv = sw = 0.0
        for v in range(max(0, int(v0) - win), min(h, int(v0) + win + 1)):
            row = v * w
            for u in range(max(0, int(u0) - win), min(w, int(u0) + win + 1)):
                i = px[row + u]
                if i > 8:
                    su += u * i
                    sv += v * i
                    sw += i
        out.append((su / sw, sv / sw) if sw > 0 else None)
    return out


def camera_check(work, log):
    """Renders marker spheres through several cameras; returns (max error px, rows)."""
    os.makedirs(work, exist_ok=True)
    rnd = random.Random(7)
    cams = [
        ("level_ref", pose_camera(0, 0, 0.0, 0.6, 0.16)),
        ("pitch20_roll5", pose_camera(20, 5, 0.01, 0.6, 0.16)),
        ("pitch30_rollm5", pose_camera(30, -5, 0.01, 0.6, 0.16)),
        ("pitch10_az30_half", pose_camera(10, 2, 0.01, 0.6, 0.16, 960, 540, azimuth_deg=30)),
        ("pitch5_roll3_double", pose_camera(5, 3, 0.02, 0.6, 0.16, 3840, 2160)),
    ]
    # And one with the principal point off the centre (a shifted lens), as render/'s sidecars.
    c = pose_camera(0, 0, 0.0, 0.6, 0.16)
    cams.append(("level_cy_shift", Camera(c.position, c.look_at, c.up, c.focal_length_mm, 1920,
                                          1080, cx_px=979.5, cy_px=700.0)))
    rows, worst = [], 0.0
    for name, cam in cams:
        pts = []
        r_m = 0.0008
        rpx = r_m * cam.focal_px() / 0.6
        while len(pts) < 15:
            p = [rnd.uniform(-0.07, 0.07), rnd.uniform(-0.07, 0.07), rnd.uniform(-0.01, 0.06)]
            uv = cam.project(p)
            m = 40 * cam.width_px / 1920
            # Apart by more than the centroid window, so that one blob is measured at a time.
            if (uv and m < uv[0] < cam.width_px - m and m < uv[1] < cam.height_px - m and
                    all(math.hypot(uv[0] - q[0], uv[1] - q[1]) > 8 * rpx for _, q in pts)):
                pts.append((p, uv))
        pov = ["#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n", cam.pov(),
               "background { rgb 0 }\n"]
        for p, _ in pts:
            pov.append("sphere { <%.6f,%.6f,%.6f>, %.5f pigment { rgb 1 } finish { emission 1 diffuse 0 ambient 0 } }\n"
                       % (p[0], p[1], p[2], r_m))
        png = os.path.join(work, "check_%s.png" % name)
        povray("".join(pov), png, cam.width_px, cam.height_px, aa=True)
        got = centroids(png, [uv for _, uv in pts], rpx)
        for (p, uv), g in zip(pts, got):
            err = math.hypot(g[0] - uv[0], g[1] - uv[1]) if g else float("inf")
            worst = max(worst, err)
            rows.append((name, p, uv, g, err))
        errs = [e for n, *_, e in rows if n == name]
        log("camera check %-20s %dx%d: %d spheres, max |centroid - projection| %.3f px, mean %.3f px"
            % (name, cam.width_px, cam.height_px, len(errs), max(errs), sum(errs) / len(errs)))
    return worst, rows
