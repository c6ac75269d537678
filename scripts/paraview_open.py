# Opens a ReposeTwin run folder in ParaView: the grains as spheres of their own radius, the plate
# and the funnel as surfaces, and the last frame's contacts as lines coloured by their
# force magnitude (every frame's with output.contact_forces = true).
#
#   pvpython scripts/paraview_open.py RUN_DIR [--screenshot PNG]   # a picture, no window
#   paraview --script=scripts/paraview_open.py                      # then RUN_DIR below, or
#   REPOSETWIN_RUN=RUN_DIR paraview --script=scripts/paraview_open.py
#
# It reads RUN_DIR/series.pvd, whose time steps hold the parts of one frame (part 0 the grains,
# then the plate, the container while it stands, the contacts). The grains are glyphed by their
# point array `radius`: ParaView's sphere glyph has radius 0.5, so the scale factor is 2.
#
# pvpython comes with Debian's python3-paraview, which conflicts with python3-vtk9: installing it
# removes libvtk9-dev, which the twin builds against. Open runs on a machine (or container) other
# than the one that builds the twin, or use the paraview GUI's Python shell.
#
# Without a screen: Debian's ParaView renders through X (it is built without an EGL or OSMesa
# offscreen path), so a screenshot with no display crashes in the first render, with
# --force-offscreen-rendering too. The script checks before it loads ParaView and refuses with
# the one command that works, under a virtual X display:
#   xvfb-run -a pvpython scripts/paraview_open.py RUN_DIR --screenshot PNG
# A ParaView built to render offscreen (EGL or OSMesa) is told so by REPOSETWIN_PARAVIEW_OFFSCREEN=1.
import os
import shlex
import shutil
import sys

pv = None  # paraview.simple, loaded once the run can be shown (load_paraview)


def open_run(run_dir):
    series = os.path.join(run_dir, "series.pvd")
    if not os.path.isfile(series):
        sys.exit(f"paraview_open: {series}: no such file (a run folder holds series.pvd)")
    reader = pv.PVDReader(registrationName="run", FileName=series)
    reader.UpdatePipeline(max(reader.TimestepValues) if reader.TimestepValues else 0.0)
    view = pv.GetActiveViewOrCreate("RenderView")
    parts = {}
    for part in range(8):
        block = pv.ExtractBlock(registrationName=f"part{part}", Input=reader)
        block.Selectors = [f"/Root/Block{part}"] if hasattr(block, "Selectors") else []
        if not hasattr(block, "Selectors"):
            block.BlockIndices = [part + 1]
        block.UpdatePipeline()
        info = block.GetDataInformation()
        if info.GetNumberOfPoints() == 0:
            pv.Delete(block)
            continue
        parts[part] = block
    grains = parts.get(0)
    if grains is None:
        sys.exit(f"paraview_open: {series}: the first part holds no grains")
    glyph = pv.Glyph(registrationName="grains", Input=grains, GlyphType="Sphere")
    glyph.ScaleArray = ["POINTS", "radius"]
    glyph.ScaleFactor = 2.0  # the sphere glyph's radius is 0.5
    glyph.GlyphMode = "All Points"
    glyph.GlyphType.ThetaResolution = 16
    glyph.GlyphType.PhiResolution = 12
    display = pv.Show(glyph, view)
    pv.ColorBy(display, ("POINTS", "material") if has_array(grains, "material") else None)
    for part, block in parts.items():
        if part == 0:
            continue
        shown = pv.Show(block, view)
        if has_array(block, "force_magnitude", cells=True):
            pv.ColorBy(shown, ("CELLS", "force_magnitude"))
            shown.LineWidth = 2.0
        else:
            shown.Opacity = 0.35
    view.CameraPosition = [0.0, -1.0, 0.25]
    view.CameraFocalPoint = [0.0, 0.0, 0.03]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    # Framed on the pile, not on the plate (many pile diameters wide).
    view.ResetCamera(*glyph.GetDataInformation().GetBounds())
    return view, parts


def has_array(source, name, cells=False):
    info = source.GetDataInformation()
    arrays = info.DataInformation.GetCellDataInformation() if cells else \
        info.DataInformation.GetPointDataInformation()
    return any(arrays.GetArrayInformation(i).GetName() == name
               for i in range(arrays.GetNumberOfArrays()))


def display_refusal(argv, env):
    """Why a screenshot cannot be rendered in this environment, with the command that renders it;
    None when it can (a display, or a ParaView declared able to render offscreen)."""
    if env.get("DISPLAY") or env.get("WAYLAND_DISPLAY") or \
            env.get("REPOSETWIN_PARAVIEW_OFFSCREEN") == "1":
        return None
    command = "xvfb-run -a pvpython scripts/paraview_open.py " + " ".join(
        shlex.quote(a) for a in argv)
    text = ("paraview_open: no display ($DISPLAY is not set), and Debian's ParaView renders "
            "through X: a screenshot here would crash. Render it under a virtual display:\n  "
            + command)
    if not shutil.which("xvfb-run"):
        text += "\n(xvfb-run is in Debian's xvfb: sudo apt-get install --no-install-recommends xvfb)"
    return text


def load_paraview():
    global pv
    try:
        from paraview import simple
    except ImportError:
        sys.exit("paraview_open: ParaView's Python is not here: run the script with pvpython. On "
                 "Debian pvpython is in python3-paraview, which conflicts with python3-vtk9 and "
                 "removes libvtk9-dev (the twin's build): install it on another machine or "
                 "container than the one that builds the twin")
    pv = simple


def main(argv):
    args = [a for a in argv if not a.startswith("--")]
    shot = None
    if "--screenshot" in argv:
        i = argv.index("--screenshot")
        if i + 1 >= len(argv):
            sys.exit("paraview_open: --screenshot needs a PNG path")
        shot = argv[i + 1]
        args = [a for a in args if a != shot]
    run_dir = args[0] if args else os.environ.get("REPOSETWIN_RUN", "")
    if not run_dir:
        sys.exit("usage: pvpython scripts/paraview_open.py RUN_DIR [--screenshot PNG]")
    if shot:
        refusal = display_refusal(argv, os.environ)
        if refusal:
            sys.exit(refusal)
    load_paraview()
    view, parts = open_run(run_dir)
    print(f"paraview_open: {run_dir}: {len(parts)} part(s) of the last frame shown")
    if shot:
        pv.SaveScreenshot(shot, view, ImageResolution=[1280, 800])
        print(f"paraview_open: wrote {shot}")
    else:
        pv.Render(view)


if __name__ == "__main__":
    main(sys.argv[1:])
