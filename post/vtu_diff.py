#!/usr/bin/env python3
"""Largest difference of every Float64 array between two `.vtu` files written by stickslip
(appended raw binary, UInt64 headers), absolute and relative to the array's largest value:

    python3 post/vtu_diff.py A.vtu B.vtu

Used to size the round-off by which a change of summation order moves the recovered fields.
Compressed files are not read (write them with `"output": {"compress": false}`, the default).
"""
import re
import struct
import sys

import numpy as np


def arrays(path):
    b = open(path, "rb").read()
    i = b.index(b'<AppendedData encoding="raw">')
    j = b.index(b"_", i) + 1
    head = b[:i].decode()
    if "compressor=" in head:
        sys.exit(f"{path}: compressed arrays are not read")
    out = {}
    pat = (r'<DataArray type="(\w+)"(?: Name="([^"]*)")? NumberOfComponents="(\d+)" '
           r'format="appended" offset="(\d+)"/>')
    for m in re.finditer(pat, head):
        kind, name, off = m.group(1), m.group(2) or "points", int(m.group(4))
        n = struct.unpack("<Q", b[j + off:j + off + 8])[0]
        dtype = {"Float64": "<f8", "UInt64": "<u8", "UInt8": "u1"}[kind]
        out[name] = np.frombuffer(b[j + off + 8:j + off + 8 + n], dtype=dtype)
    return out


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    a, b = arrays(sys.argv[1]), arrays(sys.argv[2])
    if a.keys() != b.keys():
        sys.exit(f"different arrays: {sorted(a)} against {sorted(b)}")
    for k in a:
        if a[k].dtype.kind != "f":
            same = a[k].shape == b[k].shape and bool((a[k] == b[k]).all())
            print(f"{k}: {'identical' if same else 'DIFFERENT'}")
            continue
        if a[k].shape != b[k].shape:
            print(f"{k}: different lengths {a[k].size} and {b[k].size}")
            continue
        d = float(np.abs(a[k] - b[k]).max()) if a[k].size else 0.0
        s = float(np.abs(a[k]).max()) if a[k].size else 0.0
        print(f"{k}: max |diff| {d:.3e}, max |value| {s:.3e}, relative {d / s if s else 0.0:.2e}")


if __name__ == "__main__":
    main()
