"""Files in a shared folder, a full disk and concurrent writers.

Each test plants or provokes one hazard and asserts what is on disk afterwards: a symbolic
link planted at a temporary, probe or lock name is never written through; a replaced file
keeps its mode; a second writer is refused rather than replacing the first one's result;
temporaries of killed writers, locks of refused sweeps and folders of refused commands do
not stay behind; an output that is an input is refused; a full disk during a netCDF write
ends in one line, not a segmentation fault."""

import errno
import os
import signal
import stat
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from camdyn.errors import OutputError, ParameterError, StorageError
from camdyn.io import atomic
from camdyn.io.atomic import atomic_output, check_writable, expect_new, write_text
from camdyn.io.netcdf import GuardedFile, save_netcdf

SWEEP_TOML = """
[system]
source = "sundar2014-impact"
[[vary]]
key = "motion.speed"
start = "8 Hz"
stop = "25 Hz"
num = 4
[run]
revolutions = {revolutions}
discard = 10
chunk = 2
[metrics]
names = ["poincare", "impacts", "regime"]
[output]
path = "{output}"
"""

VICTIM = "precious contents that nobody asked camdyn to touch\n"


def _dataset(samples: int = 50) -> xr.Dataset:
    t = np.arange(samples) / 1e4
    return xr.Dataset({"alpha": ("time", np.sin(t), {"units": "rad"})}, coords={"time": t})


def _victim(tmp_path: Path) -> Path:
    victim = tmp_path / "victim" / "important.txt"
    victim.parent.mkdir()
    victim.write_text(VICTIM)
    return victim


def _camdyn(*args, cwd, timeout=300):
    return subprocess.run([sys.executable, "-m", "camdyn", *args], capture_output=True, text=True, cwd=cwd,
                          timeout=timeout)


@pytest.fixture(autouse=True)
def _no_registration_left(monkeypatch):
    """Each test starts and ends with no output registered by expect_new."""
    monkeypatch.setattr(atomic, "_EXPECT_NEW", set())


# --- 1. links planted at predictable names ---------------------------------------------------

def test_link_at_the_old_temporary_name_is_not_written_through(tmp_path):
    victim = _victim(tmp_path)
    out = tmp_path / "out.nc"
    planted = tmp_path / f".out.nc.{os.getpid()}.tmp"       # the name camdyn used to write first
    planted.symlink_to(victim)
    save_netcdf(_dataset(), out)
    assert victim.read_text() == VICTIM
    assert not out.is_symlink() and xr.load_dataset(out, engine="h5netcdf")["alpha"].size == 50
    assert planted.is_symlink()                                 # someone else's link: left alone


def test_the_temporary_is_created_exclusively_by_this_process(tmp_path):
    # whatever names were planted, the file handed to the writer is a new plain file of
    # this process, made under a name nobody could predict, readable only by its owner
    out = tmp_path / "out.nc"
    with atomic_output(out) as tmp:
        st = os.lstat(tmp)
        assert stat.S_ISREG(st.st_mode) and st.st_nlink == 1 and st.st_uid == os.getuid()
        assert stat.S_IMODE(st.st_mode) == 0o600
        assert tmp.parent == tmp_path and tmp.name.startswith(f".out.nc.{os.getpid()}-")
        tmp.write_bytes(b"x")
    assert out.read_bytes() == b"x"


def test_link_at_the_old_probe_name_is_not_truncated(tmp_path):
    victim = _victim(tmp_path)
    (tmp_path / f".out.nc.{os.getpid()}.probe").symlink_to(victim)
    check_writable(tmp_path / "out.nc")
    assert victim.read_text() == VICTIM
    assert not (tmp_path / "out.nc").exists()


def test_link_at_a_json_temporary_is_not_written_through(tmp_path):
    victim = _victim(tmp_path)
    (tmp_path / f".demo.json.{os.getpid()}.tmp").symlink_to(victim)
    write_text(tmp_path / "demo.json", '{"a": 1}')
    assert victim.read_text() == VICTIM
    assert (tmp_path / "demo.json").read_text() == '{"a": 1}'


def _spec(tmp_path, revolutions=30, output="s.nc"):
    from camdyn.sweeps import load_spec

    (tmp_path / "s.toml").write_text(SWEEP_TOML.format(revolutions=revolutions, output=tmp_path / output))
    return load_spec(tmp_path / "s.toml")


def test_symlink_at_a_sweep_lock_is_replaced_not_followed(tmp_path):
    from camdyn.sweeps.store import Checkpoint

    victim = _victim(tmp_path)
    spec = _spec(tmp_path)
    lock = tmp_path / "s.nc.lock"
    lock.symlink_to(victim)
    store = Checkpoint(spec)
    try:
        assert victim.read_text() == VICTIM
        assert not lock.is_symlink() and lock.read_text() == f"pid {os.getpid()}"
    finally:
        store.close()
    assert victim.read_text() == VICTIM and not lock.exists()


def test_hard_link_at_a_sweep_lock_is_refused(tmp_path):
    from camdyn.sweeps.store import Checkpoint

    victim = _victim(tmp_path)
    spec = _spec(tmp_path)
    os.link(victim, tmp_path / "s.nc.lock")
    with pytest.raises(OutputError, match="not a lock file camdyn made"):
        Checkpoint(spec)
    assert victim.read_text() == VICTIM


# --- 2. permissions --------------------------------------------------------------------------

@pytest.mark.parametrize("mode", [0o600, 0o640, 0o604])
def test_a_replaced_file_keeps_its_mode(tmp_path, mode):
    out = tmp_path / "out.nc"
    save_netcdf(_dataset(10), out)
    out.chmod(mode)
    save_netcdf(_dataset(20), out)                            # what --force does
    assert stat.S_IMODE(out.stat().st_mode) == mode
    assert xr.load_dataset(out, engine="h5netcdf")["alpha"].size == 20
    text = tmp_path / "out.json"
    write_text(text, "1")
    text.chmod(mode)
    write_text(text, "2")
    assert stat.S_IMODE(text.stat().st_mode) == mode and text.read_text() == "2"


@pytest.mark.parametrize("umask", [0o022, 0o027, 0o002])
def test_a_new_file_gets_the_mode_the_umask_allows(tmp_path, umask):
    old = os.umask(umask)
    try:
        save_netcdf(_dataset(), tmp_path / "new.nc")
        write_text(tmp_path / "new.json", "{}")
    finally:
        os.umask(old)
    for name in ("new.nc", "new.json"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o666 & ~umask, name


# --- 3. concurrent writers -------------------------------------------------------------------

def test_a_file_created_meanwhile_is_not_replaced_without_force(tmp_path):
    out = tmp_path / "out.nc"
    expect_new(out)
    with pytest.raises(OutputError, match=r"exists \(written by another process meanwhile\); pass --force"):
        with atomic_output(out) as tmp:
            tmp.write_bytes(b"mine")
            out.write_bytes(b"the other writer's result")     # another process finished first
    assert out.read_bytes() == b"the other writer's result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.nc"]


def test_without_registration_the_write_replaces_as_before(tmp_path):
    out = tmp_path / "out.nc"
    with atomic_output(out) as tmp:
        tmp.write_bytes(b"mine")
        out.write_bytes(b"older")
    assert out.read_bytes() == b"mine"


def test_two_threads_writing_one_new_output_one_wins_one_is_refused(tmp_path):
    out = tmp_path / "out.json"
    expect_new(out)
    both_written = threading.Barrier(2)
    results = {}

    def writer(name):
        try:
            with atomic_output(out) as tmp:
                tmp.write_text(name)
                both_written.wait(10)
            results[name] = "ok"
        except OutputError as exc:
            results[name] = str(exc)

    threads = [threading.Thread(target=writer, args=(n,)) for n in ("first", "second")]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    winners = [n for n, r in results.items() if r == "ok"]
    assert len(winners) == 1, results
    loser = next(r for r in results.values() if r != "ok")
    assert "written by another process meanwhile" in loser
    assert out.read_text() == winners[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]


def test_cli_refuses_to_replace_a_result_written_during_its_run(tmp_path, monkeypatch, capsys):
    # the race made deterministic: the other writer publishes its file after this
    # command's check (the file did not exist) and before its own publication
    from camdyn.cli import common
    from camdyn.cli.app import main
    from camdyn.io import netcdf

    out = tmp_path / "run.nc"
    real = netcdf.write_netcdf

    def slow_writer(ds, path):
        real(ds, path)
        out.write_bytes(b"the other process's result")

    monkeypatch.setattr(netcdf, "write_netcdf", slow_writer)
    status = main(["simulate", "sundar2014-impact", "--revolutions", "3", "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2, err
    # on a cold numba cache the run first announces the compile (cli.common.COMPILE_NOTICE)
    lines = [line for line in err.strip().splitlines() if line != common.COMPILE_NOTICE]
    assert lines == [f"error: {out} exists (written by another process meanwhile); pass --force to overwrite"]
    assert out.read_bytes() == b"the other process's result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]
    # with --force the same race ends with this command's result
    monkeypatch.setattr(netcdf, "write_netcdf", real)
    assert main(["simulate", "sundar2014-impact", "--revolutions", "3", "--out", str(out), "--force"]) == 0
    assert "alpha" in xr.load_dataset(out, engine="h5netcdf")


def test_two_cli_writers_of_one_output_one_succeeds_one_is_refused(tmp_path):
    procs = [subprocess.Popen([sys.executable, "-m", "camdyn", "simulate", "sundar2014-impact", "--revolutions",
                               "3", "--out", "run.nc", "--json"], cwd=tmp_path, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [p.communicate(timeout=300) + (p.returncode,) for p in procs]
    assert sorted(r[2] for r in results) == [0, 2], results
    refused = next(r for r in results if r[2] == 2)
    assert refused[1].strip().count("\n") == 0 and "run.nc exists" in refused[1], refused
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]
    assert "alpha" in xr.load_dataset(tmp_path / "run.nc", engine="h5netcdf")


# --- 4. nothing left behind ------------------------------------------------------------------

_KILLED_WRITER = """
import sys, time
from camdyn.io.atomic import atomic_output
block = atomic_output(sys.argv[1])
tmp = block.__enter__()
tmp.write_bytes(b"half a result" * 1000)
print(tmp, flush=True)
time.sleep(120)
"""


def _writer_killed_mid_write(out: Path) -> Path:
    proc = subprocess.Popen([sys.executable, "-c", _KILLED_WRITER, str(out)], stdout=subprocess.PIPE, text=True)
    tmp = Path(proc.stdout.readline().strip())
    proc.send_signal(signal.SIGKILL)
    proc.wait(30)
    proc.stdout.close()
    assert tmp.exists(), "the killed writer left no temporary: nothing to test"
    return tmp


@pytest.mark.parametrize("write", ["netcdf", "text"])
def test_temporaries_of_a_killed_writer_are_removed_by_the_next_write(tmp_path, write):
    out = tmp_path / ("out.nc" if write == "netcdf" else "out.json")
    stale = _writer_killed_mid_write(out)
    # a writer still running keeps its temporary
    alive = subprocess.Popen([sys.executable, "-c", _KILLED_WRITER, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        running = Path(alive.stdout.readline().strip())
        other = tmp_path / ".other.nc.12345-00000000.abc.tmp"    # another name: not ours to judge
        other.write_bytes(b"")
        if write == "netcdf":
            save_netcdf(_dataset(), out)
        else:
            write_text(out, "{}")
        assert not stale.exists()
        assert running.exists() and other.exists()
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted([out.name, running.name, other.name])
    finally:
        alive.kill()
        alive.wait(30)
        alive.stdout.close()


#: The command line writing a record whose fsync blocks: the write is still under way
#: whenever the signal lands (it prints "writing" from inside the write).
_BLOCKED_WRITER = """
import os, sys, time
def blocked(fd):
    print("writing", flush=True)
    time.sleep(600)
os.fsync = blocked
sys.argv = ["camdyn", *sys.argv[1:]]
from camdyn.cli import run
run()
"""


def _signals_as_on_a_terminal():
    # a runner started under nohup, or with SIGINT ignored, passes the ignoring on, and
    # camdyn keeps an ignored signal ignored (as nohup asks): a terminal's defaults here
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)


@pytest.mark.parametrize("sig", [signal.SIGHUP, signal.SIGTERM, signal.SIGINT])
def test_a_command_stopped_during_its_write_leaves_no_temporary(tmp_path, sig):
    # SIGHUP is what a closed terminal sends: handled as SIGTERM and Ctrl-C are
    (tmp_path / "meas.csv").write_text("previous\n")
    proc = subprocess.Popen([sys.executable, "-c", _BLOCKED_WRITER, "synthesize", "sundar2014-impact", "--speed",
                             "16Hz", "--revolutions", "2", "--out", "meas.csv", "--force"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_signals_as_on_a_terminal)
    try:
        assert proc.stdout.readline().strip() == "writing", proc.stderr.read()
        assert len(list(tmp_path.glob(".meas.csv.*.tmp"))) == 1       # the write is under way
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    lines = [line for line in err.splitlines() if not line.startswith("warning: ")]
    assert proc.returncode == 128 + int(sig) and lines == ["interrupted"], (proc.returncode, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["meas.csv"]
    assert (tmp_path / "meas.csv").read_text() == "previous\n"


def test_a_stale_link_is_removed_without_following_it(tmp_path):
    victim = _victim(tmp_path)
    stale = _writer_killed_mid_write(tmp_path / "out.nc")
    stale.unlink()
    stale.symlink_to(victim)                 # someone put a link under the dead writer's name
    save_netcdf(_dataset(), tmp_path / "out.nc")
    assert not os.path.lexists(stale) and victim.read_text() == VICTIM


def test_half_written_parts_of_a_killed_sweep_are_removed_on_resume(tmp_path):
    # the parts are saved without a scan of their folder each (it holds one file per
    # chunk); the folder is cleaned once, when the sweep starts
    from camdyn.sweeps.store import Checkpoint

    spec = _spec(tmp_path)
    Checkpoint(spec).close()
    parts = tmp_path / "s.nc.parts"
    stale = _writer_killed_mid_write(parts / "chunk_000001.npz")
    store = Checkpoint(spec)
    try:
        assert not stale.exists()
        store.save(0, {"x": np.arange(3.0)})
        assert sorted(p.name for p in parts.iterdir()) == ["chunk_000000.npz", "manifest.json"]
    finally:
        store.close()


def test_a_lock_left_by_a_killed_sweep_is_taken_and_removed_by_the_next(tmp_path):
    from camdyn.sweeps.store import Checkpoint

    spec = _spec(tmp_path)
    holder = ("import sys, time\nfrom camdyn.sweeps import load_spec\nfrom camdyn.sweeps.store import Checkpoint\n"
              "store = Checkpoint(load_spec(sys.argv[1]))\nprint('locked', flush=True)\ntime.sleep(600)\n")
    proc = subprocess.Popen([sys.executable, "-c", holder, str(tmp_path / "s.toml")], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "locked"
        with pytest.raises(ParameterError, match=f"another sweep \\(pid {proc.pid}\\) is writing"):
            Checkpoint(spec)                                   # held: refused
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
        proc.stdout.close()
    lock = tmp_path / "s.nc.lock"
    assert lock.read_text() == f"pid {proc.pid}"             # left behind by the killed sweep
    store = Checkpoint(spec)                                 # stale: its holder is gone, so it is free
    assert lock.read_text() == f"pid {os.getpid()}"
    store.close()
    assert not lock.exists()


def test_a_sweep_refused_for_a_changed_spec_leaves_no_lock(tmp_path):
    from camdyn.sweeps.store import Checkpoint

    store = Checkpoint(_spec(tmp_path, revolutions=30))
    store.save(0, {"x": np.arange(3.0)})
    store.close()
    with pytest.raises(ParameterError, match="--restart"):
        Checkpoint(_spec(tmp_path, revolutions=31))
    assert not (tmp_path / "s.nc.lock").exists()
    Checkpoint(_spec(tmp_path, revolutions=31), restart=True).close()   # and it is free


def test_a_sweep_failing_on_a_full_disk_leaves_no_lock(tmp_path, monkeypatch):
    from camdyn.sweeps import store as store_module

    def no_space(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", no_space)          # the manifest's write fails
    with pytest.raises(StorageError, match="disk is full"):
        store_module.Checkpoint(_spec(tmp_path))
    assert not (tmp_path / "s.nc.lock").exists()
    assert not (tmp_path / "s.nc.parts").exists()


def _closed_port() -> int:
    """A local TCP port nothing listens on (bound, then released)."""
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_an_unreachable_dask_scheduler_is_refused_at_once_leaving_nothing(tmp_path):
    import time

    from camdyn.sweeps import run_sweep

    spec = _spec(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    started = time.monotonic()
    with pytest.raises(ParameterError, match=r"cannot reach the Dask scheduler at 'tcp://127.0.0.1:\d+' \(.*refused"):
        run_sweep(spec, dask=f"tcp://127.0.0.1:{_closed_port()}", progress=False)
    # refused by the address check, not after the client's 20 s connection timeout
    assert time.monotonic() - started < 15
    with pytest.raises(ParameterError, match="the host 'nohost.invalid' is not known"):
        run_sweep(spec, dask="tcp://nohost.invalid:8786", progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == before      # no parts folder, manifest or lock


def test_a_sweep_failing_before_its_first_chunk_leaves_no_parts_folder(tmp_path, monkeypatch):
    from camdyn.sweeps import execution, run_sweep

    def refused(spec):
        raise ParameterError("refused while preparing the base point")

    monkeypatch.setattr(execution, "_prepare_base", refused)
    spec = _spec(tmp_path)
    with pytest.raises(ParameterError, match="refused while preparing"):
        run_sweep(spec, workers=0, progress=False)
    assert not (tmp_path / "s.nc.parts").exists() and not (tmp_path / "s.nc.lock").exists()
    # a parts folder with saved chunks is kept for the resume
    from camdyn.sweeps.store import Checkpoint

    store = Checkpoint(spec)
    store.save(0, {"x": np.arange(3.0)})
    store.close()
    with pytest.raises(ParameterError, match="refused while preparing"):
        run_sweep(spec, workers=0, progress=False)
    assert (tmp_path / "s.nc.parts" / "chunk_000000.npz").exists()


def test_a_failed_write_removes_the_folders_it_created(tmp_path, monkeypatch):
    (tmp_path / "kept").mkdir()
    out = tmp_path / "kept" / "made" / "deeper" / "run.nc"

    def no_space(fd):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(atomic.os, "fsync", no_space)
    with pytest.raises(StorageError, match="disk is full"):
        save_netcdf(_dataset(), out)
    assert list((tmp_path / "kept").iterdir()) == []           # "kept" existed before: kept


def test_checking_an_output_creates_no_folder(tmp_path):
    out = tmp_path / "new" / "deeper" / "run.nc"
    check_writable(out, 1000)
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "a_file").write_text("")
    with pytest.raises(OutputError, match="cannot write"):
        check_writable(tmp_path / "a_file" / "run.nc")


def test_a_refused_command_leaves_no_folder_behind(tmp_path):
    (tmp_path / "old.png").write_bytes(b"an older figure")
    proc = _camdyn("simulate", "sundar2014-impact", "--revolutions", "3", "--out", "new/run.nc", "--plot", "old.png",
                   cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr == "error: old.png exists; pass --force to overwrite\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.png"]


# --- 5. an output that is an input -----------------------------------------------------------

def _rig(tmp_path, name):
    from camdyn.params.config import preset_text

    rig = tmp_path / name
    rig.write_text(preset_text("sundar2014-impact"))
    return rig, rig.read_bytes()


@pytest.mark.parametrize("force", [[], ["--force"]])
def test_an_output_that_is_the_input_is_refused_even_with_force(tmp_path, force):
    rig, before = _rig(tmp_path, "rig.nc")                    # a TOML file, whatever its name
    proc = _camdyn("simulate", "rig.nc", "--revolutions", "3", "--out", "rig.nc", *force, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: cannot write rig.nc: it is the input rig.nc"), lines
    assert rig.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rig.nc"]


def test_an_output_naming_the_input_through_a_link_or_another_path_is_refused(tmp_path):
    from camdyn.cli.common import refuse_inputs_as_outputs

    rig, _ = _rig(tmp_path, "rig.toml")
    (tmp_path / "sub").mkdir()
    (tmp_path / "alias.nc").symlink_to(rig)
    for out in [tmp_path / "alias.nc", tmp_path / "sub" / ".." / "rig.toml"]:
        with pytest.raises(OutputError, match="it is the input"):
            refuse_inputs_as_outputs([out], [rig])
    refuse_inputs_as_outputs([tmp_path / "other.nc", None], [rig])     # a different file: fine


# --- 6. a full disk during a netCDF write ----------------------------------------------------

@pytest.fixture
def tiny_disk(tmp_path):
    mount = tmp_path / "full"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(mount)], capture_output=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a 200 kB tmpfs here ({done.stderr.decode().strip() or 'not root'}); "
                    f"the segmentation fault needs a real full disk (an injected ENOSPC never reaches HDF5)")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], capture_output=True)


def test_full_disk_during_a_netcdf_write_is_one_line_not_a_segfault(tiny_disk, tmp_path):
    old = tiny_disk / "old.nc"
    old.write_bytes(os.urandom(54_000))
    before = old.read_bytes()
    proc = _camdyn("simulate", "sundar2014-impact", "--revolutions", "30", "--out", str(old), "--force",
                   cwd=tmp_path)
    assert "Segmentation fault" not in proc.stderr and "Fatal Python error" not in proc.stderr, proc.stderr[-2000:]
    assert proc.returncode == 1, proc.stderr[-2000:]
    # one error line; a warning about the run itself (30 revolutions have not settled) may precede it
    lines = [line for line in proc.stderr.splitlines() if not line.startswith("warning: ")]
    assert len(lines) == 1 and lines[0].startswith(f"error: cannot write {old}: the disk is full"), lines[:5]
    assert old.read_bytes() == before
    assert sorted(p.name for p in tiny_disk.iterdir()) == ["old.nc"]


def test_full_disk_while_writing_a_netcdf_record_is_one_line_not_a_segfault(tiny_disk, tmp_path):
    out = tiny_disk / "meas.nc"
    proc = _camdyn("synthesize", "sundar2014-friction", "--set", "cam.runout=1.75mm", "--speed", "11.55Hz",
                   "--revolutions", "200", "--sample-rate", "10kHz", "--out", str(out), cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr[-2000:]
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: cannot write {out}: the disk is full"), lines[:5]
    assert list(tiny_disk.iterdir()) == []


def test_full_disk_in_the_api_leaves_nothing_to_crash_at_exit(tiny_disk, tmp_path):
    # the same in Python: the error is raised, and collecting garbage and leaving the
    # interpreter afterwards (where the crash used to happen) end normally
    script = (f"import gc, numpy as np, xarray as xr\n"
              f"from camdyn.io.netcdf import save_netcdf\n"
              f"from camdyn.errors import StorageError\n"
              f"ds = xr.Dataset({{f'v{{i}}': ('time', np.random.default_rng(i).random(4000)) for i in range(20)}})\n"
              f"try:\n    save_netcdf(ds, {str(tiny_disk / 'x.nc')!r})\n"
              f"except StorageError as exc:\n    print('caught', exc)\n"
              f"gc.collect()\nprint('collected')\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.splitlines()[0].startswith("caught cannot write") and "collected" in proc.stdout
    assert proc.stderr == ""
    assert list(tiny_disk.iterdir()) == []



def _heap_heavy_file(sink) -> None:
    """An HDF5 file as a sweep's result is: variables on two dimensions (h5netcdf attaches
    the dimension scales at the end, reading back their lists from HDF5's global heap),
    strings (also on the heap), rows written in blocks."""
    import h5netcdf
    import h5py
    with h5netcdf.File(sink, "w") as f:
        f.dimensions = {"point": 600, "harmonic": 4}
        words = f.create_variable("status", ("point",), dtype=h5py.string_dtype())
        tables = [f.create_variable(name, ("point", "harmonic"), "f8", fillvalue=np.nan)
                  for name in ("amplitude", "phase", "power", "error")]
        for table in tables:
            table.attrs["units"] = "m"
            table.attrs["coordinates"] = "speed"
        for start in range(0, 600, 100):
            rows = np.arange(start, start + 100)
            words[start:start + 100] = np.array([f"point {i} " + "x" * (i % 37) for i in rows], dtype=object)
            for k, table in enumerate(tables):
                table[start:start + 100] = rows[:, None] * 0.5 + k + np.arange(4)
        f.attrs["title"] = "heap"


@pytest.mark.parametrize("room", [2_000, 20_000, 60_000, 120_000])
def test_a_write_that_fails_midway_leaves_hdf5_reading_what_it_wrote(tmp_path, monkeypatch, room):
    # the file as written without a failure
    whole = tmp_path / "whole.nc"
    whole.touch()
    with GuardedFile(whole) as sink:
        _heap_heavy_file(sink)
        sink.check()
    expected = whole.read_bytes()
    assert len(expected) > room
    # the same file with the disk full after `room` bytes (ENOSPC from os.write)
    written, real_write = [0], os.write

    def full_disk_write(fd, data):
        if fd == sink._fd and written[0] + len(data) > room:
            raise OSError(errno.ENOSPC, "No space left on device")
        written[0] += len(data)
        return real_write(fd, data)

    cut = tmp_path / "cut.nc"
    cut.touch()
    sink = GuardedFile(cut)
    monkeypatch.setattr(os, "write", full_disk_write)
    _heap_heavy_file(sink)   # HDF5 finishes: no error reaches it
    monkeypatch.setattr(os, "write", real_write)
    with pytest.raises(OSError) as caught:
        sink.check()
    assert caught.value.errno == errno.ENOSPC
    # what HDF5 saw (the disk, then the writes kept in memory) is the file it wrote whole:
    # every read after the failure saw what had been written, none saw zeros
    seen = bytearray(cut.read_bytes())
    seen.extend(bytes(sink._end - len(seen)))
    for page, kept in sink._pages.items():
        seen[page * sink.PAGE:(page + 1) * sink.PAGE] = kept
    assert len(seen) >= len(expected) and bytes(seen[:len(expected)]) == expected
    sink.close()


def test_after_a_failed_write_a_read_sees_what_was_written_since(tmp_path, monkeypatch):
    # measured on a full tmpfs: HDF5 failed a 32-byte write at 14,424, wrote on to 15,816,
    # then read back 64 bytes at 15,752; reading the disk's zeros there it raised
    # "bad heap index" (or crashed)
    path = tmp_path / "f"
    path.touch()
    sink = GuardedFile(path)
    sink.write(b"a" * 5000)
    real_write = os.write

    def full(fd, data):
        if fd == sink._fd:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(fd, data)

    monkeypatch.setattr(os, "write", full)
    assert sink.write(b"b" * 100) == 100             # reported as done
    sink.seek(4990)
    assert sink.write(b"c" * 20) == 20               # over the disk's bytes and the kept ones
    sink.seek(9000)
    assert sink.write(b"d" * 64) == 64               # past a gap
    assert sink.tell() == 9064
    sink.seek(4980)
    buffer = bytearray(200)
    assert sink.readinto(buffer) == 200
    assert bytes(buffer) == b"a" * 10 + b"c" * 20 + b"b" * 90 + bytes(80)
    sink.seek(8990)
    buffer = bytearray(100)
    assert sink.readinto(buffer) == 74               # the file ends where the last write ended
    assert bytes(buffer[:74]) == bytes(10) + b"d" * 64
    assert path.read_bytes() == b"a" * 5000          # nothing more reached the disk
    with pytest.raises(OSError) as caught:
        sink.check()
    assert caught.value.errno == errno.ENOSPC
    sink.close()


_SWEEP_ON_A_FULL_DISK = """
import gc, os, sys
from camdyn.errors import StorageError
from camdyn.sweeps import load_spec, run_sweep, store

disk = sys.argv[2]
assemble = store.Checkpoint.assemble

def fill_then_assemble(self, keep_parts=False):
    # the parts are on disk: fill it but for 4 kB, then write the result (HDF5, streamed)
    st = os.statvfs(disk)
    with open(os.path.join(disk, "filler"), "wb") as fh:
        fh.write(bytes(max(st.f_bavail * st.f_frsize - 4096, 0)))
    return assemble(self, keep_parts)

store.Checkpoint.assemble = fill_then_assemble
try:
    run_sweep(load_spec(sys.argv[1]), workers=0, progress=False)
except StorageError as exc:
    print("caught", exc)
gc.collect()
print("collected")
"""


def test_full_disk_while_a_sweep_streams_its_result_is_an_error_not_a_segfault(tiny_disk, tmp_path):
    spec = _spec(tmp_path, output=tiny_disk / "s.nc")
    proc = subprocess.run([sys.executable, "-c", _SWEEP_ON_A_FULL_DISK, str(tmp_path / "s.toml"), str(tiny_disk)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    caught, collected = proc.stdout.splitlines()
    assert caught.startswith(f"caught cannot write {spec.output}: the disk is full (") and collected == "collected"
    assert proc.stderr == ""
    # the parts stay for a resume; no result, temporary or lock
    assert sorted(p.name for p in tiny_disk.iterdir()) == ["filler", "s.nc.parts"]
