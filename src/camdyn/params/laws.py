"""The contact damping laws, one row each (docs/model.md §3.4; thesis 2.3.4 and 3.2).

Every property of a damping law is read from its row in :data:`TABLE`: its name and
aliases, the integer code the compiled core dispatches on
(:mod:`camdyn.model.contact`), the unit of ``contact.beta``, whether it needs the
damping ratio ``zeta`` or uses ``beta`` at all, and, for the restitution-parameterised
laws, the hysteresis factor ``chi(e)`` as a function of the coefficient of restitution
``e``. Contact validation (:class:`camdyn.params.system.Contact`), the configuration's
unit of beta (:mod:`camdyn.params.config`), the static equilibrium and the simulation
runner all read these rows.

The damping force is ``F_d = c delta_dot`` [N] with ``delta_dot`` [m/s] and:

- ``none``: ``c = 0``;
- ``viscous`` (A): ``c = 2 zeta omega_n I_P / chi*^2`` (thesis eq 2.24, 4.20);
- ``stiffness-proportional`` (B): ``c = beta F_k(delta)`` (thesis eq 2.25), beta [s/m];
- ``zhang-whiten`` (C): ``c = beta delta^0.25`` (thesis eq 2.26), beta [N s/m^1.25];
- ``stiffness-proportional-viscous`` (D): B while compressing, A while restoring (thesis eq 2.27);
- ``zhang-whiten-viscous`` (E): C while compressing, A while restoring (thesis eq 2.28);
- ``power`` (``generalized``): ``c = beta delta^n`` (thesis eq 3.2, 3.14), beta [N s/m^(n+1)];
- restitution laws: ``c = chi(e) K delta^nH / v_approach``, with ``K delta^nH = F_k`` the
  Hertz force and ``v_approach`` [m/s] the approach velocity of the contact.

The rows of the restitution laws give ``chi(e)`` as a function, as the reference writes
it, and the reference's DOI. The factor functions are plain Python with numba-compatible
arithmetic: the compiled core compiles these same functions, so each relation is
written once. numba freezes the codes and factors into its on-disk cache and checks only
the compiled modules' own files for changes: after changing a row's code or factor,
delete its cache (the ``*.nbi`` and ``*.nbc`` files in camdyn's ``__pycache__`` folders).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from camdyn.errors import ParameterError

__all__ = [
    "DampingLaw", "TABLE", "LAWS", "DAMPING_LAWS", "DAMPING_ALIASES", "RESTITUTION_LAWS",
    "FIRST_RESTITUTION_CODE", "lookup", "hunt_crossley_factor", "lankarani_nikravesh_factor",
    "flores_factor", "gonthier_factor", "hu_guo_factor",
]


def hunt_crossley_factor(e):
    """Hunt-Crossley factor ``chi(e) = 3 (1 - e) / 2`` [-] for restitution ``e`` [-]
    (doi:10.1115/1.3423596)."""
    return 1.5 * (1.0 - e)


def lankarani_nikravesh_factor(e):
    """Lankarani-Nikravesh factor ``chi(e) = 3 (1 - e^2) / 4`` [-] for restitution ``e`` [-]
    (doi:10.1115/1.2912617)."""
    return 0.75 * (1.0 - e * e)


def flores_factor(e):
    """Flores et al. factor ``chi(e) = 8 (1 - e) / (5 e)`` [-] for restitution ``e`` [-]
    (doi:10.1007/s11044-010-9237-4)."""
    return 1.6 * (1.0 - e) / e


def gonthier_factor(e):
    """Gonthier et al. factor ``chi(e) = (1 - e^2) / e`` [-] for restitution ``e`` [-]
    (doi:10.1023/B:MUBO.0000029392.21648.bc)."""
    return (1.0 - e * e) / e


def hu_guo_factor(e):
    """Hu and Guo factor ``chi(e) = 3 (1 - e) / (2 e)`` [-] for restitution ``e`` [-]
    (doi:10.1007/s11044-015-9453-z)."""
    return 1.5 * (1.0 - e) / e


@dataclass(frozen=True)
class DampingLaw:
    """One contact damping law.

    Attributes
    ----------
    name : str
        Name used in configurations (``contact.damping``).
    code : int
        Integer code stored in the compiled parameter vector.
    aliases : tuple of str
        Other accepted names (the thesis's letters A-E, ``"generalized"``).
    summary : str
        The damping coefficient ``c`` [N s/m] of ``F_d = c delta_dot``, with its equation.
    beta_unit : str
        Unit of ``contact.beta`` for pint; ``{n_plus_one!r}`` stands for ``n + 1`` where the
        unit depends on the exponent ``n`` (see :meth:`unit_of_beta`).
    needs_damping_ratio : bool
        True when the law uses the viscous coefficient of law A, and so the damping
        ratio ``zeta`` and a static contact equilibrium (thesis eq 2.24).
    uses_beta : bool
        True when ``contact.beta`` enters the force.
    restitution : callable or None
        Hysteresis factor ``chi(e)`` [-] of a restitution-parameterised law, a function
        of the coefficient of restitution ``e`` [-]; None for the other laws.
    relation : str
        ``chi(e)`` as the reference writes it.
    reference : str
        DOI of the reference giving ``chi(e)``.
    lowest_restitution : float
        Smallest accepted coefficient of restitution [-] (the factor divides by ``e``
        unless this is 0).
    """

    name: str
    code: int
    summary: str
    aliases: tuple[str, ...] = ()
    beta_unit: str = "N*s/m"
    needs_damping_ratio: bool = False
    uses_beta: bool = False
    restitution: Callable[[float], float] | None = None
    relation: str = ""
    reference: str = ""
    lowest_restitution: float = 0.0

    def unit_of_beta(self, exponent: float) -> str:
        """Unit of ``contact.beta`` [pint text] for the power-law exponent ``n`` = ``exponent`` [-]."""
        return self.beta_unit.format(n_plus_one=1.0 + exponent)


#: The damping laws, one row each, in the order of their codes.
TABLE: tuple[DampingLaw, ...] = (
    DampingLaw("none", 0, "c = 0"),
    DampingLaw("viscous", 1, "c = 2 zeta omega_n I_P / chi*^2 (thesis eq 2.24, 4.20)", aliases=("A",),
               needs_damping_ratio=True),
    DampingLaw("stiffness-proportional", 2, "c = beta F_k(delta) (thesis eq 2.25)", aliases=("B",),
               beta_unit="s/m", uses_beta=True),
    DampingLaw("zhang-whiten", 3, "c = beta delta^0.25 (thesis eq 2.26)", aliases=("C",),
               beta_unit="N*s/m**1.25", uses_beta=True),
    DampingLaw("stiffness-proportional-viscous", 4, "law B while compressing, law A while restoring (thesis eq 2.27)",
               aliases=("D",), beta_unit="s/m", uses_beta=True, needs_damping_ratio=True),
    DampingLaw("zhang-whiten-viscous", 5, "law C while compressing, law A while restoring (thesis eq 2.28)",
               aliases=("E",), beta_unit="N*s/m**1.25", uses_beta=True, needs_damping_ratio=True),
    DampingLaw("power", 6, "c = beta delta^n (thesis eq 3.2, 3.14)", aliases=("generalized",),
               beta_unit="N*s/m**{n_plus_one!r}", uses_beta=True),
    DampingLaw("hunt-crossley", 7, "c = chi(e) F_k(delta) / v_approach", restitution=hunt_crossley_factor,
               relation="3 (1 - e) / 2", reference="doi:10.1115/1.3423596"),
    DampingLaw("lankarani-nikravesh", 8, "c = chi(e) F_k(delta) / v_approach",
               restitution=lankarani_nikravesh_factor, relation="3 (1 - e^2) / 4",
               reference="doi:10.1115/1.2912617"),
    DampingLaw("flores", 9, "c = chi(e) F_k(delta) / v_approach", restitution=flores_factor,
               relation="8 (1 - e) / (5 e)", reference="doi:10.1007/s11044-010-9237-4", lowest_restitution=1e-3),
    DampingLaw("gonthier", 10, "c = chi(e) F_k(delta) / v_approach", restitution=gonthier_factor,
               relation="(1 - e^2) / e", reference="doi:10.1023/B:MUBO.0000029392.21648.bc",
               lowest_restitution=1e-3),
    DampingLaw("hu-guo", 11, "c = chi(e) F_k(delta) / v_approach", restitution=hu_guo_factor,
               relation="3 (1 - e) / (2 e)", reference="doi:10.1007/s11044-015-9453-z", lowest_restitution=1e-3),
)

#: Every accepted name and alias -> its row.
LAWS: dict[str, DampingLaw] = {
    **{row.name: row for row in TABLE},
    **{alias: row for row in TABLE for alias in row.aliases},
}
#: Law name -> code of the compiled core.
DAMPING_LAWS: dict[str, int] = {row.name: row.code for row in TABLE}
#: Alias -> law name.
DAMPING_ALIASES: dict[str, str] = {alias: row.name for row in TABLE for alias in row.aliases}
#: Names of the restitution-parameterised laws.
RESTITUTION_LAWS: tuple[str, ...] = tuple(row.name for row in TABLE if row.restitution is not None)
#: The restitution laws hold the codes from this one up; the compiled core relies on it.
FIRST_RESTITUTION_CODE: int = min(row.code for row in TABLE if row.restitution is not None)


def _check_table() -> None:
    """Refuse a table whose names clash or whose codes are not 0, 1, 2, ... in order."""
    if len(LAWS) != len(TABLE) + len(DAMPING_ALIASES):
        raise ParameterError("damping law table: a name or alias is given twice")
    if [row.code for row in TABLE] != list(range(len(TABLE))):
        raise ParameterError("damping law table: codes must be 0, 1, 2, ... in row order")
    if any((row.restitution is not None) != (row.code >= FIRST_RESTITUTION_CODE) for row in TABLE):
        raise ParameterError("damping law table: the restitution laws must come last")


_check_table()


def lookup(name: str) -> DampingLaw:
    """The row of the damping law called ``name`` (a law name or an alias).

    Raises
    ------
    ParameterError
        If no law has that name.
    """
    row = LAWS.get(name)
    if row is None:
        raise ParameterError(f"contact.damping must be one of {sorted(DAMPING_LAWS)} (or A-E), got {name!r}")
    return row
