"""Renders the von Mises stress of the last step of a `cases/fig2.json` run near the contact,
with the contact surface coloured by the shear traction q.

    xvfb-run -a pvbatch post/render_fig2.py RUN_DIR OUT.png     # RUN_DIR: the run's output dir
    xvfb-run -a pvbatch post/render_fig2.py OUT.png             # RUN_DIR defaults to out/fig2

(`apt-get install -y paraview xvfb`; pvbatch of ParaView 5.11 was used.) The view is the
undeformed geometry, |x| <= 2a and |y - 8| <= 2a around the contact centre (0, 8) with
a = 0.6808 mm (the Hertz semi-width of VM272 at P = 10 N/mm); `--a`, `--centre` and `--half`
(the half-width of the view in units of a) change it, `--size W H` the image size.
The von Mises colour range is that of the nodes inside the view.
"""

import argparse
import os
import sys
import xml.etree.ElementTree as ET

from paraview import simple, servermanager


def last_step_files(run_dir):
    """(time, bodies .vtu, contact .vtu) of the last step listed in the run's .pvd."""
    pvds = sorted(f for f in os.listdir(run_dir) if f.endswith(".pvd"))
    if len(pvds) != 1:
        sys.exit(f"render_fig2: expected one .pvd in {run_dir}, found {pvds}")
    root = ET.parse(os.path.join(run_dir, pvds[0])).getroot()
    steps = {}
    for ds in root.iter("DataSet"):
        steps.setdefault(float(ds.get("timestep")), {})[int(ds.get("part"))] = os.path.join(
            run_dir, ds.get("file")
        )
    if not steps:
        sys.exit(f"render_fig2: {pvds[0]} lists no datasets")
    t = max(steps)
    parts = steps[t]
    if 0 not in parts or 1 not in parts:
        sys.exit(f"render_fig2: the last step (t = {t}) lacks part 0 or part 1: {parts}")
    return t, parts[0], parts[1]


def range_in_box(source, array, x0, x1, y0, y1):
    """Range of a point array over the points inside the box (whole range if numpy is absent)."""
    data = servermanager.Fetch(source)
    try:
        import numpy as np
        from vtkmodules.util.numpy_support import vtk_to_numpy

        pts = vtk_to_numpy(data.GetPoints().GetData())
        val = vtk_to_numpy(data.GetPointData().GetArray(array))
        inside = (pts[:, 0] >= x0) & (pts[:, 0] <= x1) & (pts[:, 1] >= y0) & (pts[:, 1] <= y1)
        if inside.any():
            return float(val[inside].min()), float(val[inside].max())
    except ImportError:
        pass
    return data.GetPointData().GetArray(array).GetRange()


def main(argv):
    ap = argparse.ArgumentParser(description="von Mises near the contact, contact coloured by shear")
    ap.add_argument("paths", nargs="+", metavar="[RUN_DIR] OUT.png")
    ap.add_argument("--a", type=float, default=0.6808, help="contact semi-width a (mm)")
    ap.add_argument("--centre", type=float, nargs=2, default=[0.0, 8.0], metavar=("X", "Y"))
    ap.add_argument("--half", type=float, default=2.0, help="half-width of the view in units of a")
    ap.add_argument("--size", type=int, nargs=2, default=[1400, 1200], metavar=("W", "H"))
    args = ap.parse_args(argv)
    if len(args.paths) == 1:
        run_dir, out = "out/fig2", args.paths[0]
    elif len(args.paths) == 2:
        run_dir, out = args.paths
    else:
        ap.error("give RUN_DIR OUT.png (or OUT.png alone for out/fig2)")

    t, body_file, contact_file = last_step_files(run_dir)
    cx, cy = args.centre
    h = args.half * args.a
    box = (cx - h, cx + h, cy - h, cy + h)

    bodies = simple.XMLUnstructuredGridReader(FileName=[body_file])
    bodies.PointArrayStatus = ["displacement", "stress_xx", "stress_yy", "stress_xy", "stress_zz", "von_mises"]
    contact = simple.XMLUnstructuredGridReader(FileName=[contact_file])
    for src, names in ((bodies, ["von_mises"]), (contact, ["shear"])):
        src.UpdatePipeline()
        have = src.PointData.keys()
        for n in names:
            if n not in have:
                sys.exit(f"render_fig2: array `{n}` missing in {src.FileName[0]} (has {have})")

    view = simple.CreateView("RenderView")
    view.ViewSize = args.size
    view.OrientationAxesVisibility = 0
    view.Background = [1.0, 1.0, 1.0]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass

    # Bodies: von Mises, curved quadratic cells subdivided for smooth colouring.
    bd = simple.Show(bodies, view)
    bd.Representation = "Surface"
    simple.ColorBy(bd, ("POINTS", "von_mises"))
    try:
        bd.NonlinearSubdivisionLevel = 2
    except AttributeError:
        pass
    vm_lut = simple.GetColorTransferFunction("von_mises")
    vm_lut.ApplyPreset("Viridis (matplotlib)", True)
    lo, hi = range_in_box(bodies, "von_mises", *box)
    vm_lut.RescaleTransferFunction(lo, hi)
    vm_lut.AutomaticRescaleRangeMode = "Never"
    bar = simple.GetScalarBar(vm_lut, view)
    bar.Title = "von Mises (MPa)"
    bar.ComponentTitle = ""
    bar.WindowLocation = "Any Location"
    bar.Position = [0.84, 0.1]
    bar.ScalarBarLength = 0.8
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
    bar.Visibility = 1

    # Body outlines (the two arcs) for orientation.
    surf = simple.ExtractSurface(Input=bodies)
    surf.NonlinearSubdivisionLevel = 2
    edges = simple.FeatureEdges(Input=surf)
    edges.FeatureEdges = 0
    edges.NonManifoldEdges = 0
    ed = simple.Show(edges, view)
    ed.ColorArrayName = ["POINTS", ""]
    ed.AmbientColor = ed.DiffuseColor = [0.2, 0.2, 0.2]
    ed.LineWidth = 1.0

    # Contact surface: shear traction, drawn as thick lines just above the bodies.
    lines = simple.Transform(Input=simple.Tessellate(Input=contact))
    lines.Transform.Translate = [0.0, 0.0, 0.01]
    cd = simple.Show(lines, view)
    simple.ColorBy(cd, ("POINTS", "shear"))
    cd.LineWidth = 8.0
    try:
        cd.RenderLinesAsTubes = 1
    except AttributeError:
        pass
    q_lut = simple.GetColorTransferFunction("shear")
    qlo, qhi = contact.PointData["shear"].GetRange()
    if qlo < 0.0 < qhi:
        q_lut.ApplyPreset("Cool to Warm", True)
        qm = max(abs(qlo), abs(qhi))
        q_lut.RescaleTransferFunction(-qm, qm)
    else:
        # One sign: light at q = 0, dark at the largest |q|.
        q_lut.ApplyPreset("Reds" if qhi > 0.0 else "Blues", True)
        if qlo >= 0.0:
            q_lut.InvertTransferFunction()
            q_lut.RescaleTransferFunction(0.0, max(qhi, 1e-300))
        else:
            q_lut.RescaleTransferFunction(qlo, 0.0)
    q_lut.AutomaticRescaleRangeMode = "Never"
    qbar = simple.GetScalarBar(q_lut, view)
    qbar.Title = "shear q (MPa)"
    qbar.ComponentTitle = ""
    qbar.WindowLocation = "Any Location"
    qbar.Orientation = "Horizontal"
    qbar.Position = [0.2, 0.04]
    qbar.ScalarBarLength = 0.5
    qbar.TitleColor = qbar.LabelColor = [0.0, 0.0, 0.0]
    qbar.Visibility = 1

    title = simple.Text(Text=f"Fig. 2, last step (t = {t:g}): von Mises stress; contact surface coloured by "
                             f"the shear traction q\nview: {args.half:g}a either side of ({cx:g}, {cy:g}), "
                             f"a = {args.a:g} mm")
    td = simple.Show(title, view)
    td.WindowLocation = "Upper Center"
    td.Justification = "Center"
    td.FontSize = 18
    td.Color = [0.0, 0.0, 0.0]

    # Camera: parallel projection; the window shows the box (the wider side fits). The first
    # render resets the camera to the whole data, so the camera is set after it.
    w, hgt = args.size
    simple.Render(view)
    view.CameraParallelProjection = 1
    view.CameraFocalPoint = [cx, cy, 0.0]
    view.CameraPosition = [cx, cy, 10.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelScale = h * max(1.0, hgt / w)  # half-height; half-width = it × w/hgt
    simple.Render(view)
    simple.SaveScreenshot(out, view, ImageResolution=args.size)
    print(f"render_fig2: {out} from {os.path.basename(body_file)} and {os.path.basename(contact_file)} "
          f"(t = {t:g}); von Mises range in view [{lo:.4g}, {hi:.4g}] MPa, shear in [{qlo:.4g}, {qhi:.4g}] MPa")


if __name__ == "__main__":
    main(sys.argv[1:])
