"""Refit: resize a 3D garment from body A to body B, keeping the shape the designer meant.

The engine itself (not a wrapper around the command line): the same positions to
the bit as `refit resize`, numpy arrays in and out, the GIL released while it works.

    import refit
    g = refit.read_garment("dress_on_A.obj")
    binding = refit.Binding(g, refit.read_body("A.obj"),            # made once
                            features=refit.read_features("features.json"))
    r = binding.resize(refit.read_body("B.obj"))   # or binding.resize(vertices_of_B), V x 3
    refit.write_garment(g, r.positions, "dress_on_B.obj")
    print([(c["name"], c["shape_error_output"]) for c in r.report["features"]])
    refit.render(refit.read_body("B.obj"), g, r.positions, path="look.png")

Errors are refit.Error with the command line's message; the subclass says the
command line's exit class: InputError (bad input, 1), UsageError (an argument
value it refuses, 2; also a ValueError), ResourceError (out of memory, 3; also a
MemoryError). `exit_code` holds the number.

A process that resizes many large garments (a server, a batch worker) calls
refit.keep_freed_memory() once at start: freed buffers are then reused, as the
command line does.

refit.batch (the `refit-batch` command): one garment to the bodies of a manifest
on a Dask cluster. docs/python.md has the details.
"""
from ._refit import (
    Binding,
    Body,
    Error,
    Features,
    Garment,
    InputError,
    ResourceError,
    Result,
    UsageError,
    __version__,
    compare,
    keep_freed_memory,
    read_body,
    read_features,
    read_garment,
    render,
    write_garment,
)

__all__ = [
    "Binding",
    "Body",
    "Error",
    "Features",
    "Garment",
    "InputError",
    "ResourceError",
    "Result",
    "UsageError",
    "compare",
    "keep_freed_memory",
    "read_body",
    "read_features",
    "read_garment",
    "render",
    "write_garment",
]
