"""Faults a user or the machine inflicts: interrupts (SIGINT, SIGTERM, SIGKILL) during
simulate, synthesize, identify and sweep; a full disk; two sweeps on one output; damaged
checkpoints. Each test asserts the exit status, the files on disk and, where a run
resumes, a result bitwise equal to an uninterrupted run."""

import contextlib
import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import camdyn
from camdyn.errors import OutputError, ParameterError, StorageError
from camdyn.io import atomic
from camdyn.io.netcdf import save_netcdf
from camdyn.sweeps import load_spec, run_sweep
from camdyn.sweeps.store import Checkpoint

SWEEP_TOML = """
[system]
source = "sundar2014-impact"
[system.set]
"cam.runout" = "3.5 mm"
[[vary]]
key = "motion.speed"
start = "8 Hz"
stop = "25 Hz"
num = {num}
[run]
revolutions = {revolutions}
discard = 10
chunk = 2
[metrics]
names = ["poincare", "impacts", "regime"]
[output]
path = "{name}.nc"
"""


def _default_sigint():
    # Python installs its KeyboardInterrupt handler only where SIGINT is not ignored,
    # and a CI runner may start the test process with SIGINT ignored: reset it, as a
    # terminal would have it.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(args, cwd, **kw):
    return subprocess.Popen([sys.executable, "-m", "camdyn", *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, preexec_fn=_default_sigint,
                            **kw)


@pytest.fixture(autouse=True)
def _in_tmp_path(tmp_path, monkeypatch):
    """A sweep spec's relative output is the working directory's: work in the test's folder."""
    monkeypatch.chdir(tmp_path)


def _wait_for(predicate, timeout=120.0):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return False


def _children(pid: int) -> list[int]:
    """Live processes whose parent is ``pid`` (Linux /proc)."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with contextlib.suppress(OSError):
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
                if int(fields[1]) == pid and fields[0] != "Z":
                    out.append(int(entry.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


# --- interrupts ------------------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupted_simulation_exits_promptly_with_one_line_and_no_file(tmp_path, sig, status):
    out = tmp_path / "run.nc"
    proc = _start(["simulate", "sundar2014-friction", "--speed", "11.55Hz", "--revolutions", "20000",
                   "--sample-rate", "2kHz", "--out", str(out)], tmp_path)
    time.sleep(6.0)   # imports and the cached compiled code load, then well inside the integration
    assert proc.poll() is None, proc.communicate()
    sent = time.time()
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert time.time() - sent < 2.0, "the compiled loop did not stop within about a second"
    assert proc.returncode == status, err
    assert err.strip().splitlines()[-1] == "interrupted" and "Traceback" not in err, err
    assert not out.exists() and not list(tmp_path.glob(".*tmp"))


@pytest.mark.slow
def test_interrupted_sweep_stops_its_workers_and_resumes_to_the_uninterrupted_result(tmp_path):
    (tmp_path / "a.toml").write_text(SWEEP_TOML.format(num=40, revolutions=400, name="a"))
    (tmp_path / "b.toml").write_text(SWEEP_TOML.format(num=40, revolutions=400, name="b"))
    parts = tmp_path / "a.nc.parts"
    proc = _start(["sweep", "a.toml", "--workers", "2", "--quiet", "--no-plot"], tmp_path)
    assert _wait_for(lambda: len(list(parts.glob("chunk_*.npz"))) >= 2)
    workers = _children(proc.pid)
    assert workers, "the sweep runs on worker processes"
    os.killpg(proc.pid, signal.SIGINT)   # a terminal's Ctrl-C reaches the whole process group
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("interrupted:") and "run the same command again" in lines[0]
    assert _wait_for(lambda: not any(_alive(w) for w in workers), timeout=10), "orphaned workers"
    assert not (tmp_path / "a.nc").exists()
    assert not (tmp_path / "a.nc.lock").exists()
    resumed = _start(["sweep", "a.toml", "--workers", "2", "--quiet", "--no-plot"], tmp_path)
    out, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    assert "resuming:" in out
    reference = run_sweep(load_spec(tmp_path / "b.toml"), workers=0, progress=False).load()
    result = xr.load_dataset(tmp_path / "a.nc")
    for name in reference.variables:
        np.testing.assert_array_equal(result[name].values, reference[name].values, err_msg=name)


@pytest.mark.parametrize("quiet", [False, True])
def test_the_resource_tracker_of_a_sweep_keeps_standard_error_clean(quiet):
    # A lock the tracker still lists but which is gone: what it finds after an interrupt
    # terminated the workers. Without the filter it writes two warnings to stderr (the
    # control case), which broke the interrupt's one line.
    code = ("from camdyn.sweeps.execution import quiet_resource_tracker\n"
            f"if {quiet}: quiet_resource_tracker()\n"
            "from multiprocessing import resource_tracker\n"
            "resource_tracker.register('/camdyn-test-gone', 'semaphore')\n")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, env=env)
    assert done.returncode == 0, done.stderr
    if quiet:
        assert done.stderr == ""
    else:
        assert "resource_tracker" in done.stderr and "camdyn-test-gone" in done.stderr


@pytest.mark.slow
def test_sigkill_of_a_sweep_leaves_no_worker_behind(tmp_path):
    (tmp_path / "a.toml").write_text(SWEEP_TOML.format(num=40, revolutions=400, name="a"))
    proc = _start(["sweep", "a.toml", "--workers", "2", "--quiet", "--no-plot"], tmp_path)
    assert _wait_for(lambda: len(list((tmp_path / "a.nc.parts").glob("chunk_*.npz"))) >= 1)
    workers = _children(proc.pid)
    assert workers
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)   # not communicate(): the workers hold the pipes until they leave
    # each worker watches its parent every 0.5 s and leaves when it is gone
    gone = _wait_for(lambda: not any(_alive(w) for w in workers), timeout=10)
    proc.communicate(timeout=30)
    assert gone, "orphaned workers"


@pytest.mark.slow
def test_interrupted_synthesize_leaves_no_partial_record(tmp_path):
    out = tmp_path / "meas.csv"
    out.write_text("previous content\n")
    proc = _start(["synthesize", "sundar2014-friction", "--set", "cam.runout=1.75mm", "--speed", "11.55Hz",
                   "--revolutions", "20000", "--sample-rate", "2kHz", "--out", str(out), "--force"], tmp_path)
    time.sleep(6.0)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert out.read_text() == "previous content\n"
    assert not list(tmp_path.glob(".*tmp"))


# --- writes ----------------------------------------------------------------------------------

@pytest.fixture()
def small_disk(tmp_path):
    """A real 512 kB file system (tmpfs, needs root); skipped where it cannot be mounted."""
    mount = tmp_path / "disk"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=512k", "tmpfs", str(mount)],
                          capture_output=True)
    if done.returncode != 0:
        pytest.skip("cannot mount a tmpfs here (not root); the injected ENOSPC test covers the logic")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], capture_output=True)


def _record_dataset(samples: int) -> xr.Dataset:
    t = np.arange(samples) / 1e4
    return xr.Dataset({"alpha": ("time", np.sin(t), {"units": "rad"})}, coords={"time": t})


def test_full_disk_keeps_the_existing_file_and_names_the_size(small_disk):
    path = small_disk / "run.nc"
    save_netcdf(_record_dataset(100), path)
    before = path.read_bytes()
    with pytest.raises(StorageError) as info:
        save_netcdf(_record_dataset(200_000), path)     # 1.6 MB of data on a 512 kB disk
    message = str(info.value)
    assert str(path) in message and "disk is full" in message and "MB needed" in message
    assert path.read_bytes() == before
    assert sorted(p.name for p in small_disk.iterdir()) == ["run.nc"]


def test_full_disk_cli_exits_1_with_one_line(small_disk, tmp_path):
    out = small_disk / "meas.csv"
    proc = subprocess.run([sys.executable, "-m", "camdyn", "synthesize", "sundar2014-friction", "--set",
                           "cam.runout=1.75mm", "--speed", "11.55Hz", "--revolutions", "200", "--sample-rate",
                           "10kHz", "--out", str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: cannot write") and "disk is full" in lines[0]
    assert list(small_disk.iterdir()) == []


def test_injected_enospc_never_touches_the_existing_file(tmp_path, monkeypatch):
    path = tmp_path / "run.nc"
    save_netcdf(_record_dataset(100), path)
    before = path.read_bytes()

    def no_space(fd):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(atomic.os, "fsync", no_space)
    with pytest.raises(StorageError, match="disk is full"):
        save_netcdf(_record_dataset(500), path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["run.nc"]


def test_unwritable_output_is_refused_before_the_work(tmp_path):
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        if os.access(folder, os.W_OK):   # root ignores the mode; use a path below a file instead
            target = tmp_path / "a_file" / "run.nc"
            (tmp_path / "a_file").write_text("")
        else:
            target = folder / "run.nc"
        with pytest.raises(OutputError, match="cannot write"):
            atomic.check_writable(target)
        started = time.time()
        proc = subprocess.run([sys.executable, "-m", "camdyn", "simulate", "sundar2014-impact", "--revolutions",
                               "2000", "--out", str(target)], capture_output=True, text=True)
        assert proc.returncode == 2 and proc.stderr.startswith("error: cannot write")
        assert time.time() - started < 30   # refused before simulating 2000 revolutions
    finally:
        folder.chmod(0o700)


def test_a_figure_format_nobody_can_write_is_refused_before_the_simulation(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "camdyn", "simulate", "sundar2014-impact", "--revolutions", "2",
                           "--plot", str(tmp_path / "x.xyz"), "--json"], capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stdout == "" and "unknown image format 'xyz'" in proc.stderr


# --- checkpoints -----------------------------------------------------------------------------

def _small_spec(tmp_path, name="s", num=6):
    (tmp_path / f"{name}.toml").write_text(SWEEP_TOML.format(num=num, revolutions=30, name=name))
    return load_spec(tmp_path / f"{name}.toml")


def test_second_sweep_on_the_same_output_is_refused(tmp_path):
    spec = _small_spec(tmp_path)
    first = Checkpoint(spec)
    try:
        with pytest.raises(ParameterError, match="another sweep"):
            Checkpoint(spec)
    finally:
        first.close()
    Checkpoint(spec).close()   # free again once the first one is done


def test_concurrent_cli_sweeps_one_refused_one_complete(tmp_path):
    _small_spec(tmp_path, num=12)
    procs = [_start(["sweep", "s.toml", "--workers", "1", "--quiet", "--no-plot"], tmp_path) for _ in range(2)]
    results = [p.communicate(timeout=300) + (p.returncode,) for p in procs]
    codes = sorted(r[2] for r in results)
    assert codes == [0, 2], results
    refused = next(r for r in results if r[2] == 2)
    assert "another sweep" in refused[1]
    assert (tmp_path / "s.nc").exists() and not (tmp_path / "s.nc.parts").exists()


def test_parts_of_a_different_spec_are_refused_even_without_a_manifest(tmp_path):
    spec = _small_spec(tmp_path)
    store = Checkpoint(spec)
    store.save(0, {"x": np.arange(3.0)})
    store.close()
    (store.folder / "manifest.json").unlink()       # as a concurrent run could leave it
    (tmp_path / "s.toml").write_text(SWEEP_TOML.format(num=6, revolutions=31, name="s"))
    changed = load_spec(tmp_path / "s.toml")
    with pytest.raises(ParameterError, match="--restart"):
        Checkpoint(changed)
    Checkpoint(changed, restart=True).close()


def test_truncated_or_corrupt_chunk_is_detected_and_recomputed(tmp_path):
    spec = _small_spec(tmp_path)
    run_sweep(spec, workers=0, progress=False, keep_parts=True).close()
    reference = xr.load_dataset(spec.output)
    parts = Path(str(spec.output) + ".parts")
    chunk0, chunk1 = parts / "chunk_000000.npz", parts / "chunk_000001.npz"
    chunk0.write_bytes(chunk0.read_bytes()[:200])                       # truncated
    raw = bytearray(chunk1.read_bytes())
    raw[len(raw) // 2] ^= 0xFF                                          # one flipped byte
    chunk1.write_bytes(bytes(raw))
    spec.output.unlink()
    notes = []
    run_sweep(spec, workers=0, progress=False, echo=notes.append).close()
    assert sum("damaged" in n for n in notes) == 2, notes
    result = xr.load_dataset(spec.output)
    for name in reference.variables:
        np.testing.assert_array_equal(result[name].values, reference[name].values, err_msg=name)
    assert not list(tmp_path.glob(".*tmp"))


def test_api_wrong_types_and_misspelled_keys_raise_camdyn_errors():
    with pytest.raises(camdyn.errors.UnknownKeyError, match="cam.runout"):
        camdyn.load_system("sundar2014-impact", {"cam.runnout": "1 mm"})
    with pytest.raises(camdyn.errors.CamdynError):
        camdyn.simulate(camdyn.load_system("sundar2014-impact"), speed="fast")
    with pytest.raises(camdyn.errors.CamdynError):
        camdyn.simulate(camdyn.load_system("sundar2014-impact"), revolutions="many")
    with pytest.raises(camdyn.errors.CamdynError):   # a preset's name is taken; a misspelt one is refused
        camdyn.simulate("sundar2014-impakt")


@pytest.mark.slow
def test_interrupt_while_numba_compiles_is_still_an_interrupt(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "empty_cache"))   # forces compilation
    proc = _start(["simulate", "sundar2014-impact", "--revolutions", "20"], tmp_path, env=env)
    time.sleep(4.0)   # imports done, numba compiling the integrator (about 20 s from empty)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "interrupted" and "Traceback" not in err, err


API_SCRIPT = """
import sys, time, camdyn
rig = camdyn.load_system("sundar2014-friction")
camdyn.simulate(rig, speed=11.55, revolutions=2)
print("ready", flush=True)
try:
    camdyn.simulate(rig, speed=11.55, revolutions=50000, sample_rate=1000)
except KeyboardInterrupt:
    started = time.time()
    again = camdyn.simulate(rig, speed=11.55, revolutions=3)          # the interpreter is intact
    print("caught", int(again.sizes["time"]), flush=True)
    sys.exit(0)
print("not interrupted", flush=True)
sys.exit(3)
"""


@pytest.mark.slow
def test_ctrl_c_in_the_python_api_raises_keyboardinterrupt_and_the_interpreter_survives(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", API_SCRIPT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=_default_sigint, cwd=tmp_path)
    assert proc.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    sent = time.time()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, (out, err)
    assert out.startswith("caught") and time.time() - sent < 10.0, (out, err)


@pytest.fixture(scope="module")
def impact_record(tmp_path_factory):
    from camdyn.io.measurements import write_measurement
    from camdyn.records.synthesis import synthesize

    rig = camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})
    path = tmp_path_factory.mktemp("record") / "e20.nc"
    write_measurement(synthesize(rig, 15.0, revolutions=21, sample_rate=204.8e3, noise=0.01, settle=100), path)
    return path


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_identify_interrupted_at_a_random_moment(tmp_path, impact_record, seed):
    delay = np.random.default_rng(seed).uniform(1.0, 5.0)
    proc = _start(["identify", "impact-damping", "sundar2014-impact", str(impact_record), "--bootstrap", "4000",
                   "--json"], tmp_path)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode in (0, 130), err          # 0: it finished before the signal
    assert "Traceback" not in err, err
    if proc.returncode == 130:
        assert err.strip().splitlines()[-1] == "interrupted" and out == ""


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3, 4])
def test_sweep_terminated_at_a_random_moment_resumes_bitwise(tmp_path, seed):
    (tmp_path / "a.toml").write_text(SWEEP_TOML.format(num=24, revolutions=300, name="a"))
    (tmp_path / "b.toml").write_text(SWEEP_TOML.format(num=24, revolutions=300, name="b"))
    delay = np.random.default_rng(seed).uniform(2.0, 8.0)
    proc = _start(["sweep", "a.toml", "--workers", "2", "--quiet", "--no-plot"], tmp_path)
    time.sleep(delay)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode in (0, 143), err
    assert "Traceback" not in err, err
    # the result is written atomically: present means complete. It is there when the run
    # finished before the signal (exit 0) or as it came (exit 143 after the last write);
    # then there is nothing to resume, and the file itself must equal the reference
    finished = (tmp_path / "a.nc").exists()
    assert finished or proc.returncode == 143, err
    if not finished:
        resumed = _start(["sweep", "a.toml", "--workers", "2", "--quiet", "--no-plot"], tmp_path)
        _, err = resumed.communicate(timeout=300)
        assert resumed.returncode == 0, err
    reference = run_sweep(load_spec(tmp_path / "b.toml"), workers=0, progress=False).load()
    result = xr.load_dataset(tmp_path / "a.nc")
    for name in reference.variables:
        np.testing.assert_array_equal(result[name].values, reference[name].values, err_msg=name)


INLINE_SWEEP_SCRIPT = """
import sys, time
from camdyn.sweeps import run_sweep, spec_from_dict
spec = spec_from_dict({"system": {"source": "sundar2014-impact"},
                       "vary": [{"key": "motion.speed", "start": "8 Hz", "stop": "25 Hz", "num": 400}],
                       "run": {"revolutions": 400, "discard": 10, "chunk": 64},
                       "metrics": {"names": ["impacts"]}, "output": {"path": "inline.nc"}})
run_sweep(spec, workers=0, progress=False, restart=True) if len(sys.argv) > 1 else None
print("ready", flush=True)
try:
    run_sweep(spec, workers=0, progress=False)
except KeyboardInterrupt:
    print("caught", flush=True)
    sys.exit(0)
sys.exit(3)
"""


@pytest.mark.slow
def test_ctrl_c_stops_an_inline_sweep_at_once(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", INLINE_SWEEP_SCRIPT], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint, cwd=tmp_path)
    assert proc.stdout.readline().strip() == "ready"
    time.sleep(3.0)      # inside the first chunk of 64 points (several seconds of work)
    sent = time.time()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0 and out.strip() == "caught", (out, err)
    assert time.time() - sent < 2.0, "the compiled kernel did not stop between points"


@pytest.mark.parametrize("sig, status, delay", [(signal.SIGINT, 130, 0.2), (signal.SIGTERM, 143, 0.2),
                                                (signal.SIGINT, 130, 0.5), (signal.SIGINT, 130, 0.8),
                                                (signal.SIGINT, 130, 1.1)])
def test_interrupt_during_start_up_is_still_one_line(tmp_path, sig, status, delay):
    # several moments inside the imports: Ctrl-C there once ended in a death by SIGINT
    # (status -2) in about one try in five
    # 5000 revolutions at 2 kHz: a result of about 135 MB, below the large-result warning
    # (at 20 kHz, 1350 MB: on a machine whose imports end within 1.1 s the warning came
    # before the interrupt, a second line)
    proc = _start(["simulate", "sundar2014-impact", "--revolutions", "5000", "--sample-rate", "2kHz"], tmp_path)
    time.sleep(delay)    # inside the imports (or, on a fast machine, the integration)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == status, err
    assert err.strip().splitlines() == ["interrupted"], err


LATE_SIGNAL_SCRIPT = """
import os, sys, time, types
class Slow:   # a module whose clean-up takes time, as numba's and dask's do at shutdown
    def __del__(self, write=os.write, sleep=time.sleep):
        write(1, b"finalizing\\n")
        sleep(2.0)
module = types.ModuleType("slow_shutdown")
module.keep = Slow()
sys.modules["slow_shutdown"] = module
sys.argv = ["camdyn", "--version"]
from camdyn.cli import run
run()
"""


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_during_interpreter_shutdown_does_not_kill_a_finished_command(tmp_path, sig):
    # Python puts the default handlers back while it shuts down; a SIGTERM there used to
    # kill a finished sweep with status -15 (seen in CI, a signal sent as the sweep ended).
    proc = subprocess.Popen([sys.executable, "-c", LATE_SIGNAL_SCRIPT], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint, cwd=tmp_path)
    assert proc.stdout.readline().startswith("camdyn ")
    assert proc.stdout.readline().strip() == "finalizing"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0 and err == "", err
