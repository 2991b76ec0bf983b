"""Whether glibc maps a fresh large block on its own (its default, below its 32 MB
ceiling) or takes it from the heap (after refit.keep_freed_memory): shared by the
module's and the batch runner's tests, run in the process to be probed."""
import ctypes


class _MallInfo2(ctypes.Structure):
    _fields_ = [(n, ctypes.c_size_t) for n in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]


def large_block_mapped_alone(size):
    """Allocates `size` bytes and says whether glibc mapped them on their own. The block
    is kept: freeing it would move glibc's own threshold."""
    libc = ctypes.CDLL("libc.so.6")
    libc.mallinfo2.restype = _MallInfo2
    libc.malloc.restype = ctypes.c_void_p
    before = libc.mallinfo2().hblkhd  # bytes in blocks mapped on their own
    assert libc.malloc(size)
    return libc.mallinfo2().hblkhd - before >= size
