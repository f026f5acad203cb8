"""Equivalent coefficient of restitution ``xi = 1 - gamma v_a`` from measured vibration
(thesis 3.8.2), and the Hunt-Crossley damping it implies (3.8.3).

Per impact event (:mod:`camdyn.identification.impact_events`):

- the state just before impact by backward differences from the onset (eq 3.28):
  ``alpha^b = alpha(0) - tau alpha_dot(0)``, ``alpha_dot^b = alpha_dot(0) - tau alpha_ddot(0)``,
  ``Theta^b = Theta(0) - tau Omega``;
- the approach velocity ``v_a = psi_dot^b`` from eq 3.7 at that state;
- the separation velocity ``psi_dot^a``: the penetration rate just after an
  instantaneous impact at the onset, i.e. the first free-flight state after the contact
  carried back to the onset by the free flight of eq 3.9 (for an instantaneous impact
  this is the thesis's "peak of alpha_dot"; for a contact of finite length it removes the
  spring, gravity and cam motion acting during the contact);
- ``xi_i = -psi_dot^a / psi_dot^b`` (eq 3.25).

``gamma`` [s/m] is the least-squares slope of ``1 - xi`` against ``v_a`` through the
origin, and the Hunt-Crossley equivalent is ``beta = (3/2) gamma K`` [N s/m^2.5] with the
Hertz coefficient ``K`` of the contact (point: eq 3.11 at the cam's curvature at onset).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from camdyn.errors import IdentificationError
from camdyn.identification.impact_events import (
    ImpactEvents,
    impact_events,
    onset_cam_angle,
)
from camdyn.identification.impact_kernel import free_flight
from camdyn.model import layout as L
from camdyn.model.contact import (
    equivalent_radius,
    hertz_line_coefficient,
    hertz_point_coefficient,
)
from camdyn.model.geometry import contact_kinematics
from camdyn.records.schema import check_consistency

__all__ = ["RestitutionEstimate", "estimate_restitution"]


@dataclass
class RestitutionEstimate:
    """Result of :func:`estimate_restitution`."""

    gamma: float                    # slope of xi = 1 - gamma v_a [s/m]
    beta_hunt_crossley: float       # (3/2) gamma K [N s/m^2.5]
    stiffness: float                # Hertz coefficient K [N/m^1.5] (point) or [N/m] (line)
    mean_restitution: float         # mean xi [-]
    residual: float                 # rms of xi_i - (1 - gamma v_a,i) [-]
    impacts_used: int
    restitution: np.ndarray = field(repr=False)          # xi_i [-]
    approach_velocity: np.ndarray = field(repr=False)    # v_a,i [m/s]
    separation_velocity: np.ndarray = field(repr=False)  # psi_dot^a_i [m/s] (negative: separating)

    def to_dict(self) -> dict:
        return {"gamma": self.gamma, "gamma_units": "s/m", "beta_hunt_crossley": self.beta_hunt_crossley,
                "beta_hunt_crossley_units": "N*s/m^2.5", "stiffness": self.stiffness,
                "stiffness_units": "N/m^1.5", "mean_restitution": self.mean_restitution,
                "mean_approach_velocity": float(np.mean(self.approach_velocity)),
                "residual": self.residual, "impacts_used": self.impacts_used,
                "per_impact": {"restitution": self.restitution.tolist(),
                               "approach_velocity": self.approach_velocity.tolist()}}


def estimate_restitution(system, record=None, speed: float | None = None, min_impacts: int = 5,
                         events: ImpactEvents | None = None) -> RestitutionEstimate:
    """Estimate ``gamma`` of ``xi = 1 - gamma v_a`` from a periodic-impact record.

    Parameters
    ----------
    system : System
        The rig (geometry, inertia, spring, Hertz contact; ``cam.runout`` as recorded).
    record : xarray.Dataset
        ``alpha_ddot`` [rad/s^2] (or ``a_t`` [m/s^2]) over ``time`` [s]; force channels
        are not needed.
    speed : float, optional
        Cam speed [Hz]; default the record's ``speed_hz``.
    events : ImpactEvents, optional
        Already reconstructed events.

    Raises
    ------
    IdentificationError
        A record the reconstruction refuses, or impacts whose separation cannot be found.
    """
    if events is None:
        if record is not None:
            check_consistency(record, speed=speed, preset=system.name, what="the options")
        if record is not None and "runout" in record.attrs:
            system = system.with_values(**{"cam.runout": float(record.attrs["runout"])})
        events = impact_events(system, record, speed=speed, min_impacts=min_impacts, min_contact_samples=0,
                               need_forces=False)
    p = L.pack(events.system)
    tau = events.sample_interval
    omega = p[L.OMEGA]
    k = events.count
    approach = np.empty(k)
    separation = np.empty(k)
    radius = np.empty(k)
    # one impact per revolution in a periodic motion: every impact happens at the same
    # follower and cam angles. The contact condition is solved once, for the mean onset
    # angle: per impact it is badly conditioned near the cam's highest lift, where noise
    # in the angle moves the root far (or past the cam's reach) and the mean of the
    # roots is biased.
    mean_map = float(np.mean(events.alpha0_map))
    theta0, mean_onset = onset_cam_angle(p, mean_map, float(np.mean(events.alpha_dot0)), omega)
    onset = events.alpha0_map + (mean_onset - mean_map)
    for i in range(k):
        a_b = onset[i] - tau * events.alpha_dot0[i]
        ad_b = events.alpha_dot0[i] - tau * events.alpha_ddot0[i]
        th_b = theta0 - tau * omega
        kin = contact_kinematics(a_b, ad_b, th_b, omega, p)
        approach[i] = kin[1]
        radius[i] = kin[3]
        # separation: the first free-flight state after the contact, carried back to the
        # onset by the free flight of eq 3.9 (what the follower's rate would have been
        # just after an instantaneous impact; the spring, gravity and cam motion acting
        # during a contact of finite length are not the contact's restitution)
        j = min(int(round((events.contact_length[i] - events.offsets[i, 0]) / tau)) + 1,
                events.alpha[i].size - 1)
        u = events.offsets[i, 0] + j * tau
        angle = events.alpha[i][j] - events.alpha0[i] + onset[i]
        alpha_s, rate_s = free_flight(angle, events.alpha_dot[i][j], -u, p)
        separation[i] = contact_kinematics(alpha_s, rate_s, theta0, omega, p)[1]
    if np.any(approach <= 0):
        raise IdentificationError("an impact has no approach velocity at its reconstructed onset; the record "
                                  "does not match the rig (check cam.runout and the speed)")
    xi = -separation / approach
    gamma = float(np.sum(approach * (1.0 - xi)) / np.sum(approach ** 2))
    resid = float(np.sqrt(np.mean((xi - (1.0 - gamma * approach)) ** 2)))
    s = events.system
    if s.contact.kind == "point":
        stiffness = hertz_point_coefficient(L.effective_modulus(s),
                                            equivalent_radius(float(np.median(radius)), s.follower.pin_radius))
    else:
        stiffness = hertz_line_coefficient(L.effective_modulus(s), s.contact.length)
    return RestitutionEstimate(gamma=gamma, beta_hunt_crossley=1.5 * gamma * stiffness, stiffness=stiffness,
                               mean_restitution=float(np.mean(xi)), residual=resid, impacts_used=k,
                               restitution=xi, approach_velocity=approach, separation_velocity=separation)
