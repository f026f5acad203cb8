"""Coefficient tables of the steppers (class data in SciPy's terms).

Dormand-Prince 5(4) [1] with FSAL; the Rosenbrock method RODAS4 of Hairer and
Wanner [2], L-stable and stiffly accurate, which keeps its accuracy on the stiff
sustained-contact problem where an A-stable Rosenbrock method of the Kaps-Rentrop
family needed ten times more steps (measured; see docs/integrator.md).
The tests check each method's order of convergence
against a closed-form solution, so a mistyped coefficient fails them.

References
----------
[1] J. R. Dormand, P. J. Prince, A family of embedded Runge-Kutta formulae,
    J. Comput. Appl. Math. 6 (1980) 19-26, doi:10.1016/0771-050X(80)90013-3.
[3] E. Hairer, S. P. Norsett, G. Wanner, Solving Ordinary Differential Equations I:
    Nonstiff Problems, 2nd ed., Springer (1993), section II.10,
    doi:10.1007/978-3-540-78862-1.
[2] E. Hairer, G. Wanner, Solving Ordinary Differential Equations II: Stiff and
    Differential-Algebraic Problems, 2nd ed., Springer (1996), section IV.7,
    doi:10.1007/978-3-642-05221-7.
"""

import numpy as np

# Dormand-Prince 5(4): nodes, stage coefficients, 5th-order weights, error weights.
DP_C2, DP_C3, DP_C4, DP_C5 = 1 / 5, 3 / 10, 4 / 5, 8 / 9
DP_A21 = 1 / 5
DP_A31, DP_A32 = 3 / 40, 9 / 40
DP_A41, DP_A42, DP_A43 = 44 / 45, -56 / 15, 32 / 9
DP_A51, DP_A52, DP_A53, DP_A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
DP_A61, DP_A62, DP_A63, DP_A64, DP_A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
DP_B1, DP_B3, DP_B4, DP_B5, DP_B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
DP_E1, DP_E3, DP_E4, DP_E5, DP_E6, DP_E7 = (71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200,
                                           22 / 525, -1 / 40)

# Dense output of Dormand-Prince 5(4) (Shampine's continuous extension, as in DOPRI5 and
# SciPy's RK45): y(t + theta h) = y + h sum_i k_i sum_j DP_P[i, j] theta^(j+1).
DP_P = np.array([
    [1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0.0, 0.0, 0.0, 0.0],
    [0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
    [0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0.0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
    [0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
])

# DOP853 [3]: explicit Runge-Kutta 8(5,3) with a 7th-order continuous extension (three
# extra stages). The table is SciPy's transcription of Hairer's dop853.f, used as data.


def _load_dop853_table():
    """SciPy's DOP853 coefficient module, loaded from its file so that importing camdyn
    does not import all of scipy.integrate (a quarter of a second)."""
    import importlib.util
    import os

    spec = importlib.util.find_spec("scipy")
    if spec is None or not spec.submodule_search_locations:
        raise ImportError("camdyn needs SciPy (scipy>=1.11)")
    path = os.path.join(list(spec.submodule_search_locations)[0], "integrate", "_ivp", "dop853_coefficients.py")
    if not os.path.isfile(path):  # pragma: no cover - a SciPy that moved the table
        from scipy.integrate._ivp import dop853_coefficients
        return dop853_coefficients
    module_spec = importlib.util.spec_from_file_location("_camdyn_dop853_coefficients", path)
    module = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(module)
    return module


_dop = _load_dop853_table()
D8_STAGES = _dop.N_STAGES                     # 12
D8_A = np.ascontiguousarray(_dop.A, dtype=np.float64)   # (16, 16)
D8_B = np.ascontiguousarray(_dop.B, dtype=np.float64)   # (12,)
D8_C = np.ascontiguousarray(_dop.C, dtype=np.float64)   # (16,)
D8_E3 = np.ascontiguousarray(_dop.E3, dtype=np.float64)  # (13,)
D8_E5 = np.ascontiguousarray(_dop.E5, dtype=np.float64)  # (13,)
D8_D = np.ascontiguousarray(_dop.D, dtype=np.float64)   # (4, 16)


def _first_nonzero_after_column_0(rows: np.ndarray, ends) -> np.ndarray:
    """Per row, the first column after 0 whose coefficient is nonzero (the row's end where
    none is): DOP853's columns 1-4 are mostly zero, and skipping them adds only exact
    zeros less, so the sums are bitwise the same."""
    out = np.empty(rows.shape[0], dtype=np.int64)
    for r in range(rows.shape[0]):
        nz = [j for j in range(1, ends[r]) if rows[r, j] != 0.0]
        out[r] = nz[0] if nz else ends[r]
    return out


D8_A_FROM = _first_nonzero_after_column_0(D8_A, range(16))      # stage s sums k[0], k[D8_A_FROM[s]:s]
D8_B_FROM = int(_first_nonzero_after_column_0(np.vstack([D8_B, D8_E5[:12], D8_E3[:12]]), [12] * 3).min())
D8_D_FROM = int(_first_nonzero_after_column_0(D8_D, [16] * 4).min())

# RODAS4 [2]: 6-stage, order 4(3), L-stable and stiffly accurate Rosenbrock method, in
# the form
#   (I/(gamma h) - J) K_i = f(t + c_i h, y + sum_j A_ij K_j) + sum_j C_ij K_j / h + h g_i df/dt
#   y1 = y + sum_i M_i K_i,   error = K_6
# (coefficients as published by Hairer and Wanner, rodas.f, subroutine RODAS4).
RB_STAGES = 6
RB_GAMMA = 0.25
RB_C = np.array([0.0, 0.386, 0.210, 0.630, 1.0, 1.0])
RB_G = np.array([0.25, -0.1043, 0.1035, -0.3620000000000023e-01, 0.0, 0.0])
RB_A = np.zeros((6, 6))
RB_A[1, 0] = 0.1544000000000000e01
RB_A[2, 0], RB_A[2, 1] = 0.9466785280815826, 0.2557011698983284
RB_A[3, 0], RB_A[3, 1], RB_A[3, 2] = 0.3314825187068521e01, 0.2896124015972201e01, 0.9986419139977817
RB_A[4, 0], RB_A[4, 1], RB_A[4, 2], RB_A[4, 3] = (0.1221224509226641e01, 0.6019134481288629e01,
                                                  0.1253708332932087e02, -0.6878860361058950)
RB_A[5, :4] = RB_A[4, :4]
RB_A[5, 4] = 1.0
RB_CC = np.zeros((6, 6))
RB_CC[1, 0] = -0.5668800000000000e01
RB_CC[2, 0], RB_CC[2, 1] = -0.2430093356833875e01, -0.2063599157091915
RB_CC[3, 0], RB_CC[3, 1], RB_CC[3, 2] = -0.1073529058151375, -0.9594562251023355e01, -0.2047028614809616e02
RB_CC[4, 0], RB_CC[4, 1], RB_CC[4, 2], RB_CC[4, 3] = (0.7496443313967647e01, -0.1024680431464352e02,
                                                      -0.3399990352819905e02, 0.1170890893206160e02)
RB_CC[5, 0], RB_CC[5, 1], RB_CC[5, 2], RB_CC[5, 3], RB_CC[5, 4] = (
    0.8083246795921522e01, -0.7981132988064893e01, -0.3152159432874371e02, 0.1631930543123136e02,
    -0.6058818238834054e01)
RB_M = np.array([0.1221224509226641e01, 0.6019134481288629e01, 0.1253708332932087e02,
                 -0.6878860361058950, 1.0, 1.0])
