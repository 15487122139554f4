"""Arrays without reference counting, for the compiled loop.

numba passes an array as a struct whose ``meminfo`` owns the buffer, and increments and
decrements its reference count (an atomic instruction each) whenever an array crosses a
call boundary and at the branch points of the kernels inlined into the plant's
derivative; the reference-count pruning pass removes only some of them (19 increments
and 28 decrements remained in the rigid derivative's IR). With four derivatives per
plant step those atomics were a large share of the run time (docs/architecture.md,
*Borrowed arrays in the loop*, for the measured effect).

:func:`borrowed` returns a view of the same buffer with a null ``meminfo``: every
increment and decrement on it becomes a null check, and the arithmetic is unchanged
(the outputs are bit for bit the same). A borrowed view is valid only while its owner
lives and must not escape the function that made it: :func:`savant_cli.sim.engine.advance`
borrows the arrays it was called with, which its caller holds for the whole call.
"""

from __future__ import annotations

import numpy as np
from numba import carray, njit, types
from numba.extending import intrinsic


@intrinsic
def _float_pointer(typingctx, address):
    """The address (an integer) as a ``float64*``."""
    sig = types.CPointer(types.float64)(types.intp)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(signature.return_type))

    return sig, codegen


@njit(cache=True, error_model="numpy", inline="always")
def borrowed(a: np.ndarray) -> np.ndarray:
    """A reference-count-free view of the C-contiguous float64 array ``a`` (same shape,
    same buffer; see the module notes for when it is valid).

    Raises
    ------
    ValueError
        If ``a`` is not C-contiguous (a view of it would not be the same elements).
    """
    if not a.flags.c_contiguous:
        raise ValueError("borrowed() needs a C-contiguous array")
    return carray(_float_pointer(a.ctypes.data), a.shape)
