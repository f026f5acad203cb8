"""An independent, plain SciPy implementation of the same model (the oracle).

It shares no code with the compiled core: the geometry uses the cam's parametric
form (the contact point minimises ``n . X(phi)`` over the ellipse angle ``phi``)
instead of the support function, the forces are written again from docs/model.md §3, and
the hybrid system is integrated by :func:`scipy.integrate.solve_ivp` in segments
between terminal events (contact onset and separation, reversal of the sliding
velocity under Coulomb friction, peak penetration for laws D and E).

It serves two purposes: the tests compare the compiled core with it, and the
benchmarks time it as the "plain SciPy" baseline. It is slow by design (a Python
right-hand side) and supports the damping laws none, viscous (A), power, B and C.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from camdyn.params.system import System


class ReferenceModel:
    """The cam-follower equations in plain Python.

    Parameters
    ----------
    system : System
    theta0 : float
        Initial cam angle [rad].
    viscous_c : float
        Viscous damping coefficient of law A [N s/m].
    """

    def __init__(self, system: System, theta0: float, viscous_c: float = 0.0):
        s = system
        self.s = s
        self.theta0 = theta0
        self.omega = s.motion.angular_speed
        self.h = 0.5 * s.follower.width + 2.0 * s.follower.pin_radius
        self.E = np.array([s.cam.pivot_x, s.cam.pivot_y])
        inv = (1 - s.cam.poisson_ratio ** 2) / s.cam.youngs_modulus + \
              (1 - s.follower.poisson_ratio ** 2) / s.follower.youngs_modulus
        self.estar = 1.0 / inv
        self.c = viscous_c
        self.law = s.contact.damping
        if self.law not in ("none", "viscous", "power", "stiffness-proportional", "zhang-whiten"):
            raise NotImplementedError(f"the reference model does not implement damping law {self.law!r}")

    def cam(self, t):
        m = self.s.motion
        if m.kind == "constant":
            return self.theta0 + self.omega * t, self.omega
        w = 2 * math.pi * m.frequency * m.direction
        return (self.theta0 + 0.5 * m.amplitude * math.sin(w * t), 0.5 * m.amplitude * w * math.cos(w * t))

    def geometry(self, t, alpha, alpha_dot):
        """delta, delta_dot, chi, rho_c, vr, v_cam at the contact point."""
        a, b, e = self.s.cam.semi_major, self.s.cam.semi_minor, self.s.cam.runout
        th, thd = self.cam(t)
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

    def normal_force(self, delta, delta_dot, rho):
        s = self.s
        if s.contact.kind == "point":
            rd = s.follower.pin_radius
            rho_e = rho if rd == 0.0 else 1.0 / (1.0 / rho + 1.0 / rd)
            k = 4.0 / 3.0 * self.estar * math.sqrt(rho_e)
            fk = k * math.copysign(abs(delta) ** 1.5, delta)
            kdel = k * math.sqrt(abs(delta))
        else:
            k = math.pi / 4.0 * self.estar * s.contact.length
            fk = k * delta
            kdel = k
        law = self.law
        if law == "viscous":
            fd = self.c * delta_dot
        elif law == "power":
            fd = s.contact.beta * abs(delta) ** s.contact.exponent * delta_dot
        elif law == "stiffness-proportional":
            fd = s.contact.beta * kdel * abs(delta) * delta_dot  # beta F_k(delta)
        elif law == "zhang-whiten":
            fd = s.contact.beta * abs(delta) ** 0.25 * delta_dot
        else:
            fd = 0.0
        fn = fk + fd
        if s.contact.clip_adhesion:
            fn = max(fn, 0.0)
        return fn

    def derivative(self, t, y, contact, slip):
        s = self.s
        alpha, alpha_dot = y[0], y[1]
        ca = math.cos(alpha)
        fs = s.spring.stiffness * (s.spring.free_length - s.spring.ground_depth
                                   + s.spring.attachment_x * math.tan(alpha) + 0.5 * s.follower.width / ca)
        moment = s.follower.mass * s.gravity * s.follower.cg_distance * ca - fs * s.spring.attachment_x
        power = 0.0
        if contact:
            delta, delta_dot, chi, rho, vr, v_cam, n, u = self.geometry(t, alpha, alpha_dot)
            fn = self.normal_force(delta, delta_dot, rho)
            if s.friction.law == "coulomb":
                ff = s.friction.coefficient * slip * fn
            elif s.friction.law == "tanh":
                ff = s.friction.coefficient * math.tanh(s.friction.smoothing * vr) * fn
            else:
                ff = 0.0
            moment += fn * chi + ff * self.h
            power = -fn * (n @ v_cam) + ff * (u @ v_cam)
        return [alpha_dot, moment / s.follower.inertia, power]


def reference_simulate(system: System, theta0: float, y0, t_end: float, t_eval, viscous_c: float = 0.0,
                       method: str = "DOP853", rtol: float = 1e-10, atol: float = 1e-12, max_step=np.inf):
    """Integrate the reference model; returns (t_eval, y (3, n), counters dict)."""
    if system.spring.tilt != 0.0:
        raise NotImplementedError("the reference model has no spring tilt")
    model = ReferenceModel(system, theta0, viscous_c)
    t_eval = np.asarray(t_eval, float)
    y = np.array([y0[0], y0[1], 0.0], float)
    t = 0.0
    delta, delta_dot, _, _, vr, *_ = model.geometry(t, y[0], y[1])
    contact = delta > 0
    slip = 1.0 if vr >= 0 else -1.0
    out = np.full((3, t_eval.size), np.nan)
    nfev = 0
    n_events = 0
    segments = 0
    while t < t_end:
        segments += 1
        if segments > 100_000:
            raise RuntimeError("reference model: too many event segments (sticking?)")
        t_quiet = t + 1e-12 * max(1.0, t)  # no event at the very start of a segment

        def on_delta(tt, yy, t_quiet=t_quiet, contact=contact):
            if tt <= t_quiet:
                return 1.0 if contact else -1.0
            return model.geometry(tt, yy[0], yy[1])[0]
        on_delta.terminal = True
        on_delta.direction = -1 if contact else 1

        def on_vr(tt, yy, t_quiet=t_quiet, slip=slip):
            if tt <= t_quiet:
                return slip
            return model.geometry(tt, yy[0], yy[1])[4]
        on_vr.terminal = True
        on_vr.direction = -slip

        evs = [on_delta]
        if contact and system.friction.law == "coulomb":
            evs.append(on_vr)
        sol = solve_ivp(lambda tt, yy: model.derivative(tt, yy, contact, slip), (t, t_end), y,
                        method=method, rtol=rtol, atol=atol, events=evs, dense_output=True,
                        max_step=max_step)
        nfev += sol.nfev
        t_stop = sol.t[-1]
        sel = (t_eval >= t) & (t_eval <= t_stop)
        if sel.any():
            out[:, sel] = sol.sol(t_eval[sel])
        y = sol.y[:, -1].copy()
        t = t_stop
        if sol.status == 1:
            n_events += 1
            if sol.t_events[0].size:
                contact = not contact
                if contact:
                    slip = 1.0 if model.geometry(t, y[0], y[1])[4] >= 0 else -1.0
            else:
                slip = -slip
        elif sol.status != 0:
            raise RuntimeError(sol.message)
    return t_eval, out, {"nfev": nfev, "events": n_events}
