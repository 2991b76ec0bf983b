#!/usr/bin/env python3
"""Reads a DXF with ezdxf (an independent reader) and prints what the pattern
tests compare, as JSON: the layers, the $INSUNITS header, and per layer the
polylines (closed or not, their lengths) and the texts.

    /usr/bin/python3 read_dxf.py FILE.dxf

Exits 77 (CTest's skip) when ezdxf is not installed."""
import json
import math
import sys

try:
    import ezdxf
except ImportError:
    print("ezdxf is not installed (Debian: python3-ezdxf)")
    sys.exit(77)

doc = ezdxf.readfile(sys.argv[1])
auditor = doc.audit()
out = {"layers": sorted(layer.dxf.name for layer in doc.layers),
       "insunits": doc.header.get("$INSUNITS", None),
       "errors": len(auditor.errors),
       "polylines": {}, "texts": {}}
for e in doc.modelspace():
    layer = e.dxf.layer
    if e.dxftype() == "POLYLINE":
        pts = [tuple(v.dxf.location)[:2] for v in e.vertices]
        closed = e.is_closed
        n = len(pts)
        length = sum(math.dist(pts[i], pts[(i + 1) % n]) for i in range(n if closed else n - 1))
        out["polylines"].setdefault(layer, []).append({"closed": closed, "points": n, "length": length})
    elif e.dxftype() == "TEXT":
        out["texts"].setdefault(layer, []).append(e.dxf.text)
print(json.dumps(out))
