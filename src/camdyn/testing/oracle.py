"""An independent, plain SciPy implementation of the same model (the oracle).

It shares no code with the compiled core and reads no law table: the geometry uses the
cam's parametric form (the contact point minimises ``n . X(phi)`` over the ellipse angle
``phi``) instead of the support function; the forces are written again from
docs/model.md §3 and the literature; moments are cross products of force vectors with
their points of application; the hybrid system is integrated by
:func:`scipy.integrate.solve_ivp` in segments between terminal events (contact onset
and separation, and every reversal of the sliding velocity under Coulomb friction).

Damping laws, as the force ``F_d`` added to the Hertz force ``F_k`` while in contact:

- none: 0; A (viscous): ``c delta_dot`` with ``c = 2 zeta omega_n I_P / chi*^2``
  (eq 2.24, 4.20), computed here by :func:`reference_equilibrium`;
- B: ``beta F_k delta_dot`` (Hunt and Crossley's form, damping proportional to the
  elastic force; docs/model.md §3.4 and §7 choice 11); C (Zhang-Whiten): ``beta delta^(1/4) delta_dot``;
- D and E: B or C while compressing (``delta_dot > 0``), A while restoring;
- generalized: ``beta delta^n delta_dot`` (eq 3.2, 3.14);
- restitution laws: ``D(e) F_k delta_dot / v_approach``, with the hysteresis factors
  ``D(e)`` of the papers (see :data:`HYSTERESIS_FACTORS`) and ``v_approach`` the
  penetration rate at the onset of the contact, bounded below by
  ``contact.reference_velocity`` (which a run starting in contact uses).

Spring: compression of eq 3.10 / 4.14 scaled by ``cos(alpha) / cos(alpha - sigma)`` for a
spring tilted by ``sigma`` (eq 4.44), acting along ``(sin sigma, cos sigma)`` at the point
of the bar's lower face at horizontal distance ``dx`` from the pivot.

The tests compare the compiled core with it, and the benchmarks time it as the "plain
SciPy" baseline. It is slow by design (a Python right-hand side).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from camdyn.params.system import System

__all__ = ["ReferenceModel", "reference_simulate", "reference_equilibrium", "HYSTERESIS_FACTORS"]

#: Hysteresis factor ``D(e)`` [-] of ``F_d = D(e) K delta^n delta_dot / v_approach``, from
#: each paper's energy balance of an impact with restitution ``e``.
HYSTERESIS_FACTORS = {
    # Hunt & Crossley 1975, J. Appl. Mech. 42:440, lambda = 3 (1 - e) K / (2 v)
    "hunt-crossley": lambda e: 3.0 * (1.0 - e) / 2.0,
    # Lankarani & Nikravesh 1990, J. Mech. Des. 112:369, D = 3 (1 - e^2) / 4
    "lankarani-nikravesh": lambda e: 3.0 * (1.0 - e ** 2) / 4.0,
    # Flores, Machado, Silva & Martins 2011, Multibody Syst. Dyn. 25:357, D = 8 (1 - e) / (5 e)
    "flores": lambda e: 8.0 * (1.0 - e) / (5.0 * e),
    # Gonthier, McPhee, Lange & Piedboeuf 2004, Multibody Syst. Dyn. 11:209, D = (1 - e^2) / e
    "gonthier": lambda e: (1.0 - e ** 2) / e,
    # Hu & Guo 2015, Multibody Syst. Dyn. 35:131, D = 3 (1 - e) / (2 e)
    "hu-guo": lambda e: 3.0 * (1.0 - e) / (2.0 * e),
}
_VISCOUS_PARTS = ("viscous", "stiffness-proportional-viscous", "zhang-whiten-viscous")
_LAWS = ("none", "stiffness-proportional", "zhang-whiten", "power") + _VISCOUS_PARTS + tuple(HYSTERESIS_FACTORS)


def _z_moment(rx, ry, fx, fy) -> float:
    """Clockwise moment [N m] about P of the force ``(fx, fy)`` [N] applied at ``(rx, ry)`` [m]:
    minus the z component of ``r x f``."""
    return -(rx * fy - ry * fx)


class ReferenceModel:
    """The cam-follower equations in plain Python.

    Parameters
    ----------
    system : System
    theta0 : float
        Initial cam angle [rad].
    viscous_c : float, optional
        Viscous damping coefficient of laws A, D and E [N s/m]; by default this model's
        own, from :func:`reference_equilibrium` (eq 2.24).
    """

    def __init__(self, system: System, theta0: float, viscous_c: float | None = None):
        s = system
        self.s = s
        self.theta0 = theta0
        self.omega = s.motion.angular_speed
        self.h = 0.5 * s.follower.width + 2.0 * s.follower.pin_radius
        self.E = np.array([s.cam.pivot_x, s.cam.pivot_y])
        inv = (1 - s.cam.poisson_ratio ** 2) / s.cam.youngs_modulus + \
              (1 - s.follower.poisson_ratio ** 2) / s.follower.youngs_modulus
        self.estar = 1.0 / inv
        self.law = s.contact.damping
        if self.law not in _LAWS:
            raise NotImplementedError(f"the reference model does not implement damping law {self.law!r}")
        self._c = viscous_c

    @property
    def c(self) -> float:
        """Viscous coefficient of laws A, D and E [N s/m] (this model's own unless given)."""
        if self._c is None:
            self._c = 0.0
            if self.law in _VISCOUS_PARTS:
                self._c = reference_equilibrium(self.s, self.theta0)["viscous_c"]
        return self._c

    def cam(self, t):
        """Cam angle [rad] and speed [rad/s] at ``t`` [s]."""
        m = self.s.motion
        if m.kind == "constant":
            return self.theta0 + self.omega * t, self.omega
        if m.kind == "ramp":   # uniform acceleration for ramp_time, then the final speed
            w0 = 2 * math.pi * m.start_speed * m.direction
            rate = (self.omega - w0) / m.ramp_time
            tr = min(t, m.ramp_time)
            return self.theta0 + w0 * tr + 0.5 * rate * tr * tr + self.omega * (t - tr), w0 + rate * tr
        w = 2 * math.pi * m.frequency * m.direction
        return (self.theta0 + 0.5 * m.amplitude * math.sin(w * t), 0.5 * m.amplitude * w * math.cos(w * t))

    def geometry(self, t, alpha, alpha_dot):
        """delta [m], delta_dot [m/s], chi [m], rho_c [m], vr [m/s], v_cam [m/s], n, u."""
        th, thd = self.cam(t)
        return self.geometry_at(th, thd, alpha, alpha_dot)

    def geometry_at(self, th, thd, alpha, alpha_dot):
        """:meth:`geometry` at cam angle ``th`` [rad] and speed ``thd`` [rad/s]."""
        a, b, e = self.s.cam.semi_major, self.s.cam.semi_minor, self.s.cam.runout
        e1 = np.array([math.cos(th), math.sin(th)])
        e2 = np.array([-math.sin(th), math.cos(th)])
        n = np.array([math.sin(alpha), math.cos(alpha)])
        u = np.array([math.cos(alpha), -math.sin(alpha)])
        g = self.E - e * e1
        phi = math.atan2(-b * (n @ e2), -a * (n @ e1))      # minimiser of n . X(phi)
        x = g + a * math.cos(phi) * e1 + b * math.sin(phi) * e2
        delta = self.h - n @ x
        chi = u @ x
        # curvature radius of the ellipse at phi
        rho = (a * a * math.sin(phi) ** 2 + b * b * math.cos(phi) ** 2) ** 1.5 / (a * b)
        r = x - self.E
        v_cam = thd * np.array([-r[1], r[0]])
        delta_dot = -alpha_dot * chi - n @ v_cam
        xb = chi * u + self.h * n
        v_fol = -alpha_dot * np.array([-xb[1], xb[0]])
        vr = (v_cam - v_fol) @ u
        return delta, delta_dot, chi, rho, vr, v_cam, n, u

    def spring(self, alpha):
        """Spring force [N] (compression, eq 3.10 / 4.14 / 4.44) and its clockwise moment [N m]."""
        sp, wb = self.s.spring, self.s.follower.width
        sig = sp.tilt
        ca, sa = math.cos(alpha), math.sin(alpha)
        fs = sp.stiffness * (sp.free_length - sp.ground_depth + sp.attachment_x * math.tan(alpha)
                             + 0.5 * wb / ca) * ca / math.cos(alpha - sig)
        # the point of the lower face {n . X = -wb/2} at x = dx: X = s u - (wb/2) n
        along = (sp.attachment_x + 0.5 * wb * sa) / ca
        rx, ry = along * ca - 0.5 * wb * sa, -along * sa - 0.5 * wb * ca
        return fs, _z_moment(rx, ry, fs * math.sin(sig), fs * math.cos(sig))

    def hertz(self, delta, rho):
        """Elastic force ``F_k`` [N] (odd continuation below zero penetration)."""
        s = self.s
        if s.contact.kind == "point":
            rd = s.follower.pin_radius
            rho_e = rho if rd == 0.0 else 1.0 / (1.0 / rho + 1.0 / rd)
            return 4.0 / 3.0 * self.estar * math.sqrt(rho_e) * math.copysign(abs(delta) ** 1.5, delta)
        return math.pi / 4.0 * self.estar * s.contact.length * delta

    def normal_force(self, delta, delta_dot, rho, approach):
        """Normal force ``F_k + F_d`` [N] and ``F_k`` [N]; ``approach`` [m/s] as in the module text."""
        c = self.s.contact
        fk = self.hertz(delta, rho)
        d = abs(delta)
        law = self.law
        closing, opening = max(delta_dot, 0.0), min(delta_dot, 0.0)
        if law == "viscous":
            fd = self.c * delta_dot
        elif law == "stiffness-proportional":
            fd = c.beta * abs(fk) * delta_dot
        elif law == "zhang-whiten":
            fd = c.beta * d ** 0.25 * delta_dot
        elif law == "stiffness-proportional-viscous":
            fd = c.beta * abs(fk) * closing + self.c * opening
        elif law == "zhang-whiten-viscous":
            fd = c.beta * d ** 0.25 * closing + self.c * opening
        elif law == "power":
            fd = c.beta * d ** c.exponent * delta_dot
        elif law in HYSTERESIS_FACTORS:
            fd = HYSTERESIS_FACTORS[law](c.restitution) * abs(fk) * delta_dot / approach
        else:
            fd = 0.0
        fn = fk + fd
        if c.clip_adhesion:
            fn = max(fn, 0.0)
        return fn, fk

    def forces(self, t, y, contact, slip, approach):
        """``(alpha_ddot [rad/s^2], Fn [N], Ff [N], Fs [N], P_cam [W])`` in the given mode."""
        s = self.s
        alpha = y[0]
        fs, m_spring = self.spring(alpha)
        f = s.follower
        # gravity -m g y at the centre of gravity l_cg u
        moment = m_spring + _z_moment(f.cg_distance * math.cos(alpha), -f.cg_distance * math.sin(alpha),
                                      0.0, -f.mass * s.gravity)
        fn = ff = power = 0.0
        if contact:
            delta, delta_dot, chi, rho, vr, v_cam, n, u = self.geometry(t, alpha, y[1])
            fn = self.normal_force(delta, delta_dot, rho, approach)[0]
            if s.friction.law == "coulomb":
                ff = s.friction.coefficient * slip * fn
            elif s.friction.law == "tanh":
                ff = s.friction.coefficient * math.tanh(s.friction.smoothing * vr) * fn
            (ux, uy), (nx, ny) = u.tolist(), n.tolist()
            # at the follower's contact point chi u + h n, the cam pushes along -n, drags along u
            moment += _z_moment(chi * ux + self.h * nx, chi * uy + self.h * ny, ff * ux - fn * nx, ff * uy - fn * ny)
            power = -fn * (n @ v_cam) + ff * (u @ v_cam)
        return moment / f.inertia, fn, ff, fs, power

    def derivative(self, t, y, contact, slip, approach):
        """``d(alpha, alpha_dot, W_cam)/dt``."""
        acc, _, _, _, power = self.forces(t, y, contact, slip, approach)
        return [y[1], acc, power]


def reference_equilibrium(system: System, theta0: float) -> dict:
    """Static contact equilibrium with the cam frozen at ``theta0`` [rad] (eqs 2.16-2.18) and
    the viscous coefficient of law A (eq 2.24).

    Friction keeps the sign (and, for tanh friction, the magnitude) of ``mu`` at the
    touching angle with the cam turning and the follower still; damping is left out.

    Returns
    -------
    dict
        ``angle`` [rad], ``moment_arm`` [m], ``penetration`` [m], ``omega_n`` [rad/s]
        (``sqrt(k / I_P)`` with ``k = -dM/dalpha``), ``viscous_c`` [N s/m].
    """
    plain = system.with_values(**{"contact.damping": "none", "contact.clip_adhesion": False})
    model = ReferenceModel(plain, theta0, 0.0)
    _, thd = model.cam(0.0)

    def delta_at(a):
        return model.geometry_at(theta0, 0.0, a, 0.0)[0]

    grid = np.linspace(-0.6, 0.6, 241)
    vals = np.array([delta_at(a) for a in grid])
    idx = np.nonzero((vals[:-1] > 0) & (vals[1:] <= 0))[0]
    i = idx[np.argmin(np.abs(grid[idx]))]
    a_touch = brentq(delta_at, grid[i], grid[i + 1], xtol=1e-16, rtol=1e-15)
    vr = model.geometry_at(theta0, thd, a_touch, 0.0)[4]
    fr = system.friction
    mu = 0.0
    if fr.law == "coulomb":
        mu = math.copysign(fr.coefficient, vr)
    elif fr.law == "tanh":
        mu = fr.coefficient * math.tanh(fr.smoothing * vr)

    def moment(a, penetration=None):
        """Clockwise moment [N m] at ``a`` [rad]; ``penetration(a)`` [m] overrides the geometry's."""
        delta, _, chi, rho, _, _, n, u = model.geometry_at(theta0, 0.0, a, 0.0)
        if penetration is not None:
            delta = penetration(a)
        fs, m = model.spring(a)
        r_g = system.follower.cg_distance * u
        m += _z_moment(r_g[0], r_g[1], 0.0, -system.follower.mass * system.gravity)
        if delta > 0:
            fn = model.hertz(delta, rho)
            xb, fc = chi * u + model.h * n, fn * (mu * u - n)
            m += _z_moment(xb[0], xb[1], fc[0], fc[1])
        return m

    if moment(a_touch) >= 0.0:
        raise ValueError("the follower rests off the cam: no contact equilibrium")
    lo = a_touch - 1e-4
    while moment(lo) < 0.0:
        lo -= 2.0 * (a_touch - lo)
    alpha = brentq(moment, lo, a_touch, xtol=1e-17, rtol=1e-15)
    delta, _, chi, *_ = model.geometry_at(theta0, 0.0, alpha, 0.0)
    # The penetration is a difference of lengths ~1e5 times larger, so its rounding
    # (~3e-17 m) would swamp a difference quotient over steps small enough for the Hertz
    # law. Its first-order change is exact instead: d delta / d alpha = -u . Xc = -chi (the
    # contact point minimises n . X, so only n turns, and dn/dalpha = u); the rest of the
    # moment (arm, curvature, spring, gravity) varies on a scale of radians. Central
    # difference over 1e-4 of the penetration: truncation ~4e-10 relative.
    # (The quotient divides by the steps as rounded: alpha ~ 0.1 rad holds a 1e-9 rad step
    # to only 1e-7.)
    step = 1e-4 * delta / chi
    linear = lambda a: delta - chi * (a - alpha)
    up, down = alpha + step, alpha - step
    k = -(moment(up, linear) - moment(down, linear)) / (up - down)
    omega = math.sqrt(k / system.follower.inertia)
    c = 2.0 * system.contact.damping_ratio * omega * system.follower.inertia / chi ** 2
    return {"angle": alpha, "moment_arm": chi, "penetration": delta, "omega_n": omega, "viscous_c": c}


def _events(model, t, contact, slip, coulomb):
    """Terminal events of a segment starting at ``t`` [s]: the penetration leaving its sign,
    and under Coulomb friction in contact the sliding velocity leaving ``slip``."""
    t_quiet = t + 1e-12 * max(1.0, t)  # no event at the very start of a segment

    def on_delta(tt, yy):
        if tt <= t_quiet:
            return 1.0 if contact else -1.0
        return model.geometry(tt, yy[0], yy[1])[0]
    on_delta.terminal = True
    on_delta.direction = -1 if contact else 1

    def on_vr(tt, yy):
        if tt <= t_quiet:
            return slip
        return model.geometry(tt, yy[0], yy[1])[4]
    on_vr.terminal = True
    on_vr.direction = -slip
    return [on_delta, on_vr] if coulomb else [on_delta]


def _sample_forces(model, t_eval, out, mask, mode, fn_out, ff_out):
    """Fill ``fn_out``, ``ff_out`` [N] at the samples ``mask`` of one segment."""
    for j in np.nonzero(mask)[0]:
        _, fn, ff, _, _ = model.forces(t_eval[j], out[:, j], *mode)
        fn_out[j] = fn
        ff_out[j] = ff


def reference_simulate(system: System, theta0: float, y0, t_end: float, t_eval, viscous_c: float | None = None,
                       method: str = "DOP853", rtol: float = 1e-10, atol: float = 1e-12, max_step=np.inf,
                       forces: bool = False):
    """Integrate the reference model.

    Parameters
    ----------
    system : System
    theta0 : float
        Initial cam angle [rad].
    y0 : sequence
        Initial ``(alpha [rad], alpha_dot [rad/s])``.
    t_end : float
        End time [s].
    t_eval : array_like
        Sample times [s].
    viscous_c : float, optional
        Viscous coefficient [N s/m] of laws A, D, E; default this model's own.
    max_step : float
        Largest step [s]. Events are seen only as sign changes between steps: to be sure
        of catching a brief (low-velocity) contact or flight, cap the step below it.
    forces : bool
        Also return ``Fn`` and ``Ff`` [N] at the samples (in the info dict).

    Returns
    -------
    t_eval : ndarray
    y : ndarray, shape (3, n)
        ``alpha`` [rad], ``alpha_dot`` [rad/s], cam work [J].
    info : dict
        ``nfev``, ``events`` (count), ``log`` (list of ``(t [s], kind)`` with kind
        ``"onset"``, ``"separation"`` or ``"reversal"``), and ``Fn``, ``Ff`` if asked.
    """
    model = ReferenceModel(system, theta0, viscous_c)
    v_ref = system.contact.reference_velocity
    t_eval = np.asarray(t_eval, float)
    y = np.array([y0[0], y0[1], 0.0], float)
    t = 0.0
    delta, delta_dot, _, _, vr, *_ = model.geometry(t, y[0], y[1])
    contact = delta > 0
    slip = 1.0 if vr >= 0 else -1.0
    approach = v_ref
    out = np.full((3, t_eval.size), np.nan)
    fn_out = np.full(t_eval.size, np.nan)
    ff_out = np.full(t_eval.size, np.nan)
    nfev = 0
    log = []
    while t < t_end:
        if len(log) > 100_000:
            raise RuntimeError("reference model: too many event segments (sticking?)")
        evs = _events(model, t, contact, slip, contact and system.friction.law == "coulomb")
        mode = (contact, slip, approach)
        sol = solve_ivp(lambda tt, yy: model.derivative(tt, yy, *mode), (t, t_end), y,
                        method=method, rtol=rtol, atol=atol, events=evs, dense_output=True,
                        max_step=max_step)
        nfev += sol.nfev
        t_stop = sol.t[-1]
        sel = (t_eval >= t) & (t_eval <= t_stop)
        if sel.any():
            out[:, sel] = sol.sol(t_eval[sel])
            if forces:
                _sample_forces(model, t_eval, out, sel, mode, fn_out, ff_out)
        y = sol.y[:, -1].copy()
        t = t_stop
        if sol.status == 1:
            if sol.t_events[0].size:
                contact = not contact
                log.append((t, "onset" if contact else "separation"))
                if contact:
                    _, delta_dot, _, _, vr, *_ = model.geometry(t, y[0], y[1])
                    slip = 1.0 if vr >= 0 else -1.0
                    approach = max(delta_dot, v_ref)
            else:
                slip = -slip
                log.append((t, "reversal"))
        elif sol.status != 0:
            raise RuntimeError(sol.message)
    info = {"nfev": nfev, "events": len(log), "log": log}
    if forces:
        info["Fn"], info["Ff"] = fn_out, ff_out
    return t_eval, out, info
