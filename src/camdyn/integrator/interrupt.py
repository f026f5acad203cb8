"""Ctrl-C inside compiled loops.

While a compiled (nopython) function runs, the Python interpreter does not run: a Ctrl-C
only sets CPython's "signal pending" flag, and the ``KeyboardInterrupt`` would come when
the whole simulation has returned (minutes later, or after an exception raised on the
way out had left the interpreter in a bad state). :func:`interrupted` lets a compiled
loop ask CPython itself, through its C API ``PyErr_CheckSignals``, whether a signal
handler raised: the loop then stops, clears the pending exception, and returns a status
that its Python caller turns into ``KeyboardInterrupt`` (or the CLI's exit status 130).

The call is a few nanoseconds (an atomic flag read when nothing is pending); loops call
it every :data:`POLL_STEPS` steps. It needs the GIL, so it is only for functions compiled
without ``nogil``; nogil kernels (the sweep workers') run in child processes that the
parent stops instead. The function is resolved by name when the compiled code is loaded,
so numba's on-disk cache keeps working.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

__all__ = ["interrupted", "POLL_STEPS"]

#: Steps between two polls of the interrupt flag in a compiled loop [-].
POLL_STEPS = 256


@intrinsic
def interrupted(typingctx):
    """1 if a signal handler raised (Ctrl-C), else 0; the pending exception is cleared.

    Call only from nopython code that holds the GIL (not ``nogil=True``).
    """
    signature = types.int32()

    def codegen(context, builder, sig, args):
        int32 = ir.IntType(32)
        check = cgutils.get_or_insert_function(builder.module, ir.FunctionType(int32, []), "PyErr_CheckSignals")
        clear = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(), []), "PyErr_Clear")
        failed = builder.icmp_signed("!=", builder.call(check, []), int32(0))
        with builder.if_then(failed, likely=False):
            builder.call(clear, [])
        return builder.select(failed, int32(1), int32(0))

    return signature, codegen
