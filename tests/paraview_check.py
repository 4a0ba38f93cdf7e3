#!/usr/bin/env python3
"""Opens each run's `.pvd` series the way ParaView does and checks the documented arrays.

    pvpython tests/paraview_check.py OUTDIR [OUTDIR ...]      # ParaView's own PVD reader
    python3  tests/paraview_check.py OUTDIR [OUTDIR ...]      # VTK's XML reader (pip install vtk)

OUTDIR is a `stickslip run` output directory holding one `.pvd` (or the `.pvd` itself).
For every time step of the series it checks that part 0 (bodies, 6-node triangles, VTK type 22)
and part 1 (contact surface, 3-node lines, VTK type 21) are listed and readable, and that
every documented array is present with the right number of components, one tuple per point
(or cell) and only finite values. `--reader paraview|vtk` forces one reader; the default uses
ParaView when `paraview.simple` can be imported, else VTK. Exit status 0 when everything
passes, 1 on any failure (each failure is printed), 2 when no reader is available.

With VTK alone there is no `.pvd` reader (it is a ParaView class), so the collection is parsed
here with ElementTree and each listed `.vtu` is opened with vtkXMLUnstructuredGridReader.
"""

import argparse
import math
import os
import sys
import xml.etree.ElementTree as ET

BODY_POINT = {
    "displacement": 3,
    "stress_xx": 1,
    "stress_yy": 1,
    "stress_xy": 1,
    "stress_zz": 1,
    "von_mises": 1,
}
BODY_CELL = {"body_id": 1}
CONTACT_POINT = {
    "pressure": 1,
    "shear": 1,
    "gap": 1,
    "slip": 1,
    "slip_increment": 1,
    "status": 1,
    "mu": 1,
    "q_over_p": 1,
    "slip_mu": 1,
    "slip_rate": 1,
    "traction": 3,
    "normal": 3,
}
PARTS = {
    0: ("bodies", 22, BODY_POINT, BODY_CELL),
    1: ("contact", 21, CONTACT_POINT, {}),
}


class Failures:
    def __init__(self):
        self.items = []

    def add(self, where, msg):
        self.items.append(f"{where}: {msg}")
        print(f"  FAIL {where}: {msg}")


def find_pvd(arg):
    if os.path.isfile(arg) and arg.endswith(".pvd"):
        return arg
    if os.path.isdir(arg):
        # `<stem>_time.pvd` lists a run's steps integrated in time at their physical time;
        # the run's series is the other one.
        pvds = sorted(
            f for f in os.listdir(arg) if f.endswith(".pvd") and not f.endswith("_time.pvd")
        )
        if len(pvds) == 1:
            return os.path.join(arg, pvds[0])
        if not pvds:
            raise ValueError(f"{arg}: no .pvd file in this directory")
        raise ValueError(f"{arg}: more than one .pvd file: {', '.join(pvds)}")
    raise ValueError(f"{arg}: neither a directory nor a .pvd file")


def parse_pvd(pvd, fails):
    """Returns {time: {part: absolute file}} from the collection, checking its structure."""
    try:
        root = ET.parse(pvd).getroot()
    except ET.ParseError as e:
        fails.add(pvd, f"not valid XML: {e}")
        return {}
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        fails.add(pvd, f"root is <{root.tag} type={root.get('type')!r}>, expected <VTKFile type=\"Collection\">")
        return {}
    steps = {}
    base = os.path.dirname(os.path.abspath(pvd))
    for ds in root.iter("DataSet"):
        try:
            t = float(ds.get("timestep"))
            part = int(ds.get("part"))
        except (TypeError, ValueError):
            fails.add(pvd, f"DataSet without numeric timestep/part: {ds.attrib}")
            continue
        f = ds.get("file")
        if not f:
            fails.add(pvd, f"DataSet at t={t} part {part} has no file")
            continue
        path = os.path.join(base, f)
        if not os.path.isfile(path):
            fails.add(pvd, f"t={t} part {part}: listed file {f} does not exist")
        if part in steps.setdefault(t, {}):
            fails.add(pvd, f"t={t}: part {part} listed twice")
        steps[t][part] = path
    if not steps:
        fails.add(pvd, "the collection lists no DataSet")
    for t, parts in sorted(steps.items()):
        if set(parts) != {0, 1}:
            fails.add(pvd, f"t={t}: parts {sorted(parts)} listed, expected part 0 (bodies) and part 1 (contact)")
    return steps


def values_finite(arr):
    """(all finite?, first bad index) for a vtkDataArray, with numpy when available."""
    try:
        from vtkmodules.util import numpy_support
        import numpy as np

        a = numpy_support.vtk_to_numpy(arr)
        ok = np.isfinite(a)
        if ok.all():
            return True, None
        return False, int(np.argmin(ok.reshape(-1)))
    except ImportError:
        n = arr.GetNumberOfTuples() * arr.GetNumberOfComponents()
        for i in range(n):
            if not math.isfinite(arr.GetValue(i)):
                return False, i
        return True, None


def check_dataset(ds, part, where, fails, report):
    name, ctype, point_arrays, cell_arrays = PARTS[part]
    if ds is None:
        fails.add(where, f"{name}: no dataset")
        return
    if not ds.IsA("vtkUnstructuredGrid"):
        fails.add(where, f"{name}: a {ds.GetClassName()}, expected vtkUnstructuredGrid")
        return
    npts, ncells = ds.GetNumberOfPoints(), ds.GetNumberOfCells()
    if npts == 0 or ncells == 0:
        fails.add(where, f"{name}: {npts} points, {ncells} cells")
        return
    types = {ds.GetCellType(i) for i in range(ncells)}
    if types != {ctype}:
        fails.add(where, f"{name}: cell types {sorted(types)}, expected only {ctype}")
    pts = ds.GetPoints().GetData()
    ok, bad = values_finite(pts)
    if not ok:
        fails.add(where, f"{name}: point coordinate {bad} not finite")
    for assoc, attrs, expected, count in (
        ("point", ds.GetPointData(), point_arrays, npts),
        ("cell", ds.GetCellData(), cell_arrays, ncells),
    ):
        for arr_name, ncomp in expected.items():
            arr = attrs.GetArray(arr_name)
            if arr is None:
                present = [attrs.GetArrayName(i) for i in range(attrs.GetNumberOfArrays())]
                fails.add(where, f"{name}: {assoc} array '{arr_name}' missing (present: {present})")
                continue
            if arr.GetNumberOfComponents() != ncomp:
                fails.add(where, f"{name}: {assoc} array '{arr_name}' has {arr.GetNumberOfComponents()} components, expected {ncomp}")
            if arr.GetNumberOfTuples() != count:
                fails.add(where, f"{name}: {assoc} array '{arr_name}' has {arr.GetNumberOfTuples()} tuples, expected {count}")
            ok, bad = values_finite(arr)
            if not ok:
                fails.add(where, f"{name}: {assoc} array '{arr_name}' value {bad} is not finite")
            report.add((part, assoc, arr_name, ncomp))
    return npts, ncells


def read_vtu_vtk(path):
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

    r = vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    if not r.CanReadFile(path):
        return None, f"vtkXMLUnstructuredGridReader cannot read {os.path.basename(path)}"
    r.Update()
    if r.GetErrorCode() != 0:
        return None, f"reader error code {r.GetErrorCode()} on {os.path.basename(path)}"
    return r.GetOutput(), None


def check_run_vtk(pvd, fails):
    steps = parse_pvd(pvd, fails)
    report = set()
    for t, parts in sorted(steps.items()):
        for part in sorted(parts):
            if part not in PARTS:
                fails.add(pvd, f"t={t}: unexpected part {part}")
                continue
            where = f"{os.path.basename(parts[part])} (t={t:g}, part {part})"
            ds, err = read_vtu_vtk(parts[part])
            if err:
                fails.add(where, err)
                continue
            check_dataset(ds, part, where, fails, report)
    return len(steps), report


def composite_leaves(ds):
    """The non-composite datasets inside a (possibly nested) multiblock."""
    if ds is None:
        return []
    if ds.IsA("vtkMultiBlockDataSet") or ds.IsA("vtkMultiPieceDataSet"):
        out = []
        n = ds.GetNumberOfBlocks() if ds.IsA("vtkMultiBlockDataSet") else ds.GetNumberOfPieces()
        for i in range(n):
            out += composite_leaves(ds.GetBlock(i) if ds.IsA("vtkMultiBlockDataSet") else ds.GetPiece(i))
        return out
    return [ds]


def check_run_paraview(pvd, fails):
    from paraview import simple, servermanager

    steps = parse_pvd(pvd, fails)  # the structure check, independent of the reader
    reader = simple.PVDReader(FileName=os.path.abspath(pvd))
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues) if reader.TimestepValues is not None else []
    if isinstance(reader.TimestepValues, float):
        times = [reader.TimestepValues]
    if sorted(times) != sorted(steps):
        fails.add(pvd, f"ParaView sees time steps {times}, the collection lists {sorted(steps)}")
    report = set()
    for t in times or [0.0]:
        reader.UpdatePipeline(t)
        data = servermanager.Fetch(reader)
        where = f"{os.path.basename(pvd)} at t={t:g}"
        if data is None or not data.IsA("vtkMultiBlockDataSet"):
            fails.add(where, f"PVDReader output is {data.GetClassName() if data else None}, expected a multiblock of part 0 and part 1")
            continue
        if data.GetNumberOfBlocks() != 2:
            fails.add(where, f"PVDReader output has {data.GetNumberOfBlocks()} blocks, expected 2 (part 0 bodies, part 1 contact)")
        for part in range(min(2, data.GetNumberOfBlocks())):
            # ParaView nests each part's pieces in a multiblock of its own: unwrap it.
            leaves = composite_leaves(data.GetBlock(part))
            if len(leaves) != 1:
                fails.add(f"{where}, part {part}", f"{len(leaves)} datasets in the part, expected 1")
                continue
            check_dataset(leaves[0], part, f"{where}, part {part}", fails, report)
    simple.Delete(reader)
    return len(times), report


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("outdirs", nargs="+", metavar="OUTDIR")
    ap.add_argument("--reader", choices=["auto", "paraview", "vtk"], default="auto")
    args = ap.parse_args()

    reader = args.reader
    if reader in ("auto", "paraview"):
        try:
            from paraview import simple  # noqa: F401
            import paraview

            reader = "paraview"
            desc = f"ParaView {paraview.__version__ if hasattr(paraview, '__version__') else ''} PVDReader (paraview.simple)".replace("  ", " ")
            try:
                from paraview import servermanager
                v = servermanager.vtkSMProxyManager
                desc = f"ParaView {v.GetVersionMajor()}.{v.GetVersionMinor()}.{v.GetVersionPatch()} PVDReader (paraview.simple)"
            except Exception:
                pass
        except ImportError as e:
            if args.reader == "paraview":
                print(f"paraview_check: ParaView's Python modules are not available ({e}); run with pvpython", file=sys.stderr)
                return 2
            reader = "vtk"
    if reader == "vtk":
        try:
            import vtkmodules
            from vtkmodules.vtkCommonCore import vtkVersion
        except ImportError as e:
            print(f"paraview_check: neither ParaView nor VTK Python modules are available ({e}); "
                  "install one: `pip install vtk` or `apt-get install paraview` and use pvpython", file=sys.stderr)
            return 2
        desc = f"VTK {vtkVersion.GetVTKVersion()} vtkXMLUnstructuredGridReader (.pvd parsed with ElementTree)"
    print(f"paraview_check: reader: {desc}")

    fails = Failures()
    for arg in args.outdirs:
        try:
            pvd = find_pvd(arg)
        except ValueError as e:
            fails.add(arg, str(e))
            continue
        print(f"{pvd}:")
        n0 = len(fails.items)
        nsteps, report = (check_run_paraview if reader == "paraview" else check_run_vtk)(pvd, fails)
        for part in (0, 1):
            arrs = sorted((a, n, c) for p, a, n, c in report if p == part)
            label = PARTS[part][0]
            text = ", ".join(f"{n}({c}{'' if a == 'point' else ', cell'})" for a, n, c in arrs)
            print(f"  part {part} ({label}): {text}")
        status = "ok" if len(fails.items) == n0 else f"{len(fails.items) - n0} failure(s)"
        print(f"  {nsteps} time step(s), parts 0 and 1 each: {status}")

    if fails.items:
        print(f"paraview_check: FAILED, {len(fails.items)} failure(s):", file=sys.stderr)
        for f in fails.items:
            print(f"  {f}", file=sys.stderr)
        return 1
    print(f"paraview_check: all {len(args.outdirs)} run(s) pass")
    return 0


if __name__ == "__main__":
    sys.exit(main())
