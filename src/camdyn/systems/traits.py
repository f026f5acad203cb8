"""Traits of the registered models that the steady-state analyses ask for, answered here
where models are told apart (the compiled dispatch is :mod:`camdyn.systems.registry`;
these are plain Python, read once per orbit or curve).

- :func:`has_cam_channels`: whether a model's derived output channels are the rocking
  cam-follower's (``alpha_ddot``, ``Fn``, ``Nx``, ``Ny``, ... of
  :mod:`camdyn.model.outputs`), so that their cam harmonics can be computed from its
  samples;
- :func:`contact_mode_slot`: the mode slot that says "in contact", for a model whose
  smooth orbits (harmonic balance) are balanced in sustained contact;
- :func:`unclipped`: the parameter vector with the contact law's clip of adhesive
  (negative) force turned off, so that the force passes smoothly through zero and its
  smallest value over an orbit is a smooth test function of contact loss.
"""

from __future__ import annotations

import numpy as np

from camdyn.model import layout as L
from camdyn.systems.models import CAM_FOLLOWER

__all__ = ["contact_mode_slot", "has_cam_channels", "unclipped"]


def has_cam_channels(system_id: int) -> bool:
    """Whether model ``system_id``'s derived channels are the rocking cam-follower's."""
    return system_id == CAM_FOLLOWER


def contact_mode_slot(system_id: int) -> int | None:
    """The mode slot whose 1 means contact (:data:`camdyn.model.layout.MODE_CONTACT` for the
    cam-follower); None for a model without one."""
    return L.MODE_CONTACT if system_id == CAM_FOLLOWER else None


def unclipped(system_id: int, p: np.ndarray) -> np.ndarray | None:
    """A copy of the parameter vector ``p`` with the contact law's clip of adhesive force
    off (:data:`camdyn.model.layout.CLIP` = 0); None for a model without such a clip."""
    if system_id != CAM_FOLLOWER:
        return None
    p = np.array(p, dtype=float)
    p[L.CLIP] = 0.0
    return p
