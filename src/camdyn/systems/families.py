"""The families of models, told apart from a configuration's name or file: the one place
where camdyn asks which family a source belongs to (the simulation's entry,
:func:`camdyn.io.sources.simulate`, asks here).

- ``"model"``: a model of the model protocol in a Python file, ``FILE.py:NAME``;
- ``"mechanism"``: a configuration with a ``[mechanism]`` table (driven cam, flexible
  pivot, two followers);
- ``"translating"``: a translating follower on a cam profile (``[follower] kind``);
- ``"rocking"``: a rocking roller or knife edge on a cam profile;
- ``"cam-follower"``: the thesis's rocking flat-faced follower, the default.
"""

from __future__ import annotations

__all__ = ["FAMILIES", "family_of"]

#: The families, in the order they are told apart.
FAMILIES = ("model", "mechanism", "translating", "rocking", "cam-follower")


def family_of(source) -> str:
    """The family of a configuration's name or file: ``"model"``, ``"mechanism"``,
    ``"translating"``, ``"rocking"``, or ``"cam-follower"`` (the thesis's rocking
    flat-faced follower, also for a name or file that is none of these: its reader
    then says what is wrong)."""
    from camdyn.params.mechanism import is_mechanism
    from camdyn.params.profiles import declared_kind, is_translating
    from camdyn.systems.model_files import is_model_reference

    if is_model_reference(source):
        return "model"
    if is_mechanism(source):
        return "mechanism"
    if is_translating(source):
        return "translating"
    return "rocking" if declared_kind(source) == "rocking" else "cam-follower"
