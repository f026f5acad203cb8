import sys, numpy as np, camdyn, math, time
from camdyn.simulation.runner import prepare
from camdyn.integrator import driver
def go(sysid, p, y0, t0, t1, label):
    ref, _, evr, c = driver.integrate(sysid, p, y0.copy(), t0, t1, np.array([t1]), 1e-13, 1e-16, (t1-t0)/10, 3, 10**8, 10**5, False)
    print(label, "events", len(evr))
    for rtol in (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        row = []
        for m in (3, 4):
            t_ = time.perf_counter()
            y, _, ev, c = driver.integrate(sysid, p, y0.copy(), t0, t1, np.array([t1]), rtol, rtol*1e-4, (t1-t0)/10, m, 10**8, 10**5, False)
            dt = time.perf_counter() - t_
            row.append(f"m{m} err {abs(y[-1,0]-ref[-1,0])/max(abs(ref[:,0]).max(),1e-300):.2e} rhs {c[driver.COUNT_RHS]} acc {c[0]} rej {c[1]} jac {c[driver.COUNT_JACOBIANS]} ev {len(ev)} st {c[driver.COUNT_STATUS]} {dt*1e3:.1f}ms")
        print(f"{rtol:.0e}", " | ".join(row))
p = np.array([2*math.pi*3, 0.02, 1.0, 2*math.pi*1.3, 0.0])
go(1, p, np.array([0.1, 0.0, 0.0]), 0.0, 10.0, "osc")
for preset, ov, sp in [("sundar2014-friction", {"cam.runout": "1.75 mm"}, 11.55), ("sundar2014-impact", {"cam.runout": "3.5 mm"}, 16.0)]:
    s = camdyn.load_system(preset, ov).with_values(**{"motion.speed": sp})
    prep = prepare(s)
    go(0, prep.p, prep.y0.copy(), 0.0, 30/sp, preset)
