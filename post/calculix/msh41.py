"""Minimal reader for gmsh MSH 4.1 files (binary little-endian or ASCII), numpy only.

Reads what the VM272 meshes of this project contain: $PhysicalNames, $Entities, $Nodes and
$Elements (see meshes/README.md for the binary layout). Returns

    Mesh(nodes, groups)

where `nodes` is an (N+1, 3) float array indexed by node tag (row 0 unused; tags are
contiguous from 1 in the project meshes, which is checked), and `groups` maps a physical
group name to a list of (gmsh element type, (n, k) int64 connectivity array of node tags,
element tags array).
"""
from __future__ import annotations

import dataclasses

import numpy as np

# number of nodes of the gmsh element types we may meet
NODES_PER_TYPE = {1: 2, 2: 3, 8: 3, 9: 6, 15: 1}


@dataclasses.dataclass
class Mesh:
    nodes: np.ndarray
    groups: dict


class _Buf:
    """Cursor over the raw bytes of the file."""

    def __init__(self, data: bytes):
        self.data = data
        self.pos = 0

    def line(self) -> str:
        end = self.data.index(b"\n", self.pos)
        s = self.data[self.pos:end].decode("ascii", errors="replace").strip()
        self.pos = end + 1
        return s

    def arr(self, dtype, count):
        dt = np.dtype(dtype).newbyteorder("<")
        nbytes = dt.itemsize * count
        a = np.frombuffer(self.data, dtype=dt, count=count, offset=self.pos)
        self.pos += nbytes
        return a

    def skip_to(self, marker: bytes):
        self.pos = self.data.index(marker, self.pos) + len(marker)
        # end of that line
        self.pos = self.data.index(b"\n", self.pos) + 1


def read_msh41(path: str) -> Mesh:
    with open(path, "rb") as fh:
        data = fh.read()
    b = _Buf(data)
    if b.line() != "$MeshFormat":
        raise ValueError(f"{path}: not a gmsh file")
    ver, ftype, dsize = b.line().split()
    if not ver.startswith("4.1"):
        raise ValueError(f"{path}: MSH version {ver}, need 4.1")
    binary = ftype == "1"
    if binary:
        if int(dsize) != 8:
            raise ValueError(f"{path}: size_t of {dsize} bytes not supported")
        one = b.arr(np.int32, 1)[0]
        if one != 1:
            raise ValueError(f"{path}: big-endian binary not supported")
        b.line()  # rest of the line after the endianness int
    b.skip_to(b"$EndMeshFormat")

    phys_names = {}  # (dim, tag) -> name
    ent_phys = {}  # (dim, entity tag) -> list of physical tags
    nodes = None
    elem_blocks = []  # (dim, entity tag, type, elem tags, conn)

    while b.pos < len(data):
        try:
            sec = b.line()
        except ValueError:
            break
        if not sec.startswith("$"):
            continue
        if sec == "$PhysicalNames":
            n = int(b.line())
            for _ in range(n):
                parts = b.line().split(maxsplit=2)
                phys_names[(int(parts[0]), int(parts[1]))] = parts[2].strip('"')
            b.skip_to(b"$EndPhysicalNames")
        elif sec == "$Entities":
            if binary:
                counts = b.arr(np.uint64, 4)
                for _ in range(int(counts[0])):  # points
                    tag = int(b.arr(np.int32, 1)[0])
                    b.arr(np.float64, 3)
                    npt = int(b.arr(np.uint64, 1)[0])
                    ent_phys[(0, tag)] = list(b.arr(np.int32, npt))
                for dim in (1, 2, 3):
                    for _ in range(int(counts[dim])):
                        tag = int(b.arr(np.int32, 1)[0])
                        b.arr(np.float64, 6)
                        npt = int(b.arr(np.uint64, 1)[0])
                        ent_phys[(dim, tag)] = [int(v) for v in b.arr(np.int32, npt)]
                        nb = int(b.arr(np.uint64, 1)[0])
                        b.arr(np.int32, nb)
            else:
                counts = [int(v) for v in b.line().split()]
                for dim in range(4):
                    for _ in range(counts[dim]):
                        v = b.line().split()
                        tag = int(v[0])
                        k = 4 if dim == 0 else 7
                        npt = int(v[k])
                        ent_phys[(dim, tag)] = [int(t) for t in v[k + 1:k + 1 + npt]]
            b.skip_to(b"$EndEntities")
        elif sec == "$Nodes":
            if binary:
                nblocks, nnodes, _mn, mx = (int(v) for v in b.arr(np.uint64, 4))
            else:
                nblocks, nnodes, _mn, mx = (int(v) for v in b.line().split())
            nodes = np.full((mx + 1, 3), np.nan)
            seen = 0
            for _ in range(nblocks):
                if binary:
                    _dim, _tag, param = (int(v) for v in b.arr(np.int32, 3))
                    n = int(b.arr(np.uint64, 1)[0])
                    tags = b.arr(np.uint64, n).astype(np.int64)
                    xyz = b.arr(np.float64, 3 * n).reshape(n, 3)
                else:
                    _dim, _tag, param, n = (int(v) for v in b.line().split())
                    tags = np.array([int(b.line()) for _ in range(n)], dtype=np.int64)
                    xyz = np.array([[float(t) for t in b.line().split()[:3]] for _ in range(n)])
                    xyz = xyz.reshape(n, 3)
                if param:
                    raise ValueError(f"{path}: parametric nodes not supported")
                nodes[tags] = xyz
                seen += n
            if seen != nnodes:
                raise ValueError(f"{path}: read {seen} nodes, header says {nnodes}")
            b.skip_to(b"$EndNodes")
        elif sec == "$Elements":
            if binary:
                nblocks, _ne, _mn, _mx = (int(v) for v in b.arr(np.uint64, 4))
            else:
                nblocks, _ne, _mn, _mx = (int(v) for v in b.line().split())
            for _ in range(nblocks):
                if binary:
                    dim, etag, etype = (int(v) for v in b.arr(np.int32, 3))
                    n = int(b.arr(np.uint64, 1)[0])
                    k = NODES_PER_TYPE[etype]
                    raw = b.arr(np.uint64, n * (k + 1)).astype(np.int64).reshape(n, k + 1)
                else:
                    dim, etag, etype, n = (int(v) for v in b.line().split())
                    k = NODES_PER_TYPE[etype]
                    raw = np.array([[int(t) for t in b.line().split()] for _ in range(n)],
                                   dtype=np.int64).reshape(n, k + 1)
                elem_blocks.append((dim, etag, etype, raw[:, 0].copy(), raw[:, 1:].copy()))
            b.skip_to(b"$EndElements")
        else:
            # unknown section: skip it
            end = "$End" + sec[1:]
            b.skip_to(end.encode())

    if nodes is None:
        raise ValueError(f"{path}: no $Nodes section")
    if np.isnan(nodes[1:]).any():
        raise ValueError(f"{path}: node tags are not contiguous from 1")

    groups: dict = {}
    for dim, etag, etype, tags, conn in elem_blocks:
        for ptag in ent_phys.get((dim, etag), []):
            name = phys_names.get((dim, ptag), f"{dim}:{ptag}")
            groups.setdefault(name, []).append((etype, conn, tags))
    return Mesh(nodes=nodes, groups=groups)


def group_conn(mesh: Mesh, name: str, etype: int) -> np.ndarray:
    """All connectivity rows of element type `etype` in physical group `name`."""
    if name not in mesh.groups:
        raise KeyError(f"physical group {name!r} not in mesh (have {sorted(mesh.groups)})")
    rows = [c for t, c, _ in mesh.groups[name] if t == etype]
    if not rows:
        types = sorted({t for t, _, _ in mesh.groups[name]})
        raise ValueError(f"group {name!r} has no elements of gmsh type {etype} (has {types})")
    return np.concatenate(rows)
