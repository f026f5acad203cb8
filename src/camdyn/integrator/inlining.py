"""The numba compiler pipeline of the driver: functions inlined without copying their
arguments.

numba's IR inlining (``inline="always"``) binds each argument of an inlined call to a
new variable, ``param = argument``, and each such copy of an array costs an atomic
reference-count increment and decrement at every call: in the driver's loop, split
into inlined steps, they made each step about a fifth slower than the same code
written in place. The pass :class:`ForwardCopies` removes the copies after inlining,
so that the split loop compiles to the code of the loop written whole.

A copy ``a = b`` is forwarded (every use of ``a`` reads ``b``) when ``a`` and ``b`` are
each assigned once in the function and the copy dominates every use of ``a``: then
``b`` cannot change between the copy and a use (a new value of ``b`` would need its one
assignment to run again, on a path that would reach the use without the copy).
"""

from __future__ import annotations

from collections import Counter

from numba.core import ir, postproc
from numba.core.analysis import compute_cfg_from_blocks
from numba.core.compiler import CompilerBase, DefaultPassBuilder
from numba.core.compiler_machinery import FunctionPass, register_pass
from numba.core.ir_utils import build_definitions, replace_vars
from numba.core.untyped_passes import InlineInlinables

__all__ = ["ForwardCopies", "InlinedPipeline", "forwardable_copies"]


def forwardable_copies(blocks: dict) -> dict:
    """The copies ``a = b`` of a function's IR that can be forwarded.

    Parameters
    ----------
    blocks : dict
        The function's IR blocks (numba ``ir.Block`` by label), before SSA.

    Returns
    -------
    dict
        ``{a: b}``: the name of each forwardable copy's target, and its source variable.
    """
    assigned = Counter()
    uses = {}
    for label, block in blocks.items():
        for index, stmt in enumerate(block.body):
            if isinstance(stmt, ir.Assign):
                assigned[stmt.target.name] += 1
            for var in stmt.list_vars():
                if not (isinstance(stmt, ir.Assign) and var is stmt.target):
                    uses.setdefault(var.name, []).append((label, index))
    dominators = compute_cfg_from_blocks(blocks).dominators()
    copies = {}
    for label, block in blocks.items():
        for index, stmt in enumerate(block.body):
            if not (isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Var)):
                continue
            target, source = stmt.target.name, stmt.value
            dominated = all((at == label and after > index) or (at != label and label in dominators[at])
                            for at, after in uses.get(target, ()))
            if assigned[target] == 1 and assigned[source.name] == 1 and dominated:
                copies[target] = source
    return copies


@register_pass(mutates_CFG=False, analysis_only=False)
class ForwardCopies(FunctionPass):
    """Forward the copies of :func:`forwardable_copies` and remove them."""

    _name = "camdyn_forward_copies"

    def __init__(self):
        FunctionPass.__init__(self)

    def run_pass(self, state):
        """Forward the copies of ``state.func_ir``; True if any was removed."""
        blocks = state.func_ir.blocks
        copies = forwardable_copies(blocks)
        if not copies:
            return False
        for block in blocks.values():
            block.body = [stmt for stmt in block.body
                          if not (isinstance(stmt, ir.Assign) and stmt.target.name in copies)]
        replace_vars(blocks, copies)
        state.func_ir._definitions = build_definitions(blocks)
        postproc.PostProcessor(state.func_ir).run()
        return True


class InlinedPipeline(CompilerBase):
    """numba's nopython pipeline with :class:`ForwardCopies` after the inlining of
    ``inline="always"`` functions (``numba.njit(pipeline_class=InlinedPipeline)``)."""

    def define_pipelines(self):
        """numba's nopython pipeline, with :class:`ForwardCopies` added."""
        pipeline = DefaultPassBuilder.define_nopython_pipeline(self.state)
        pipeline.add_pass_after(ForwardCopies, InlineInlinables)
        pipeline.finalize()
        return [pipeline]
