"""Every command that writes several files writes them as one set (``OutputPlan.as_one_set``, one
``OutputSet`` in ``core/_files.py``): a failure, a concurrent run or a signal in the middle of putting the set in
place leaves the old set or the new one, never a mix, and no file of an earlier run beside a new set."""

from __future__ import annotations

import fcntl
import os
import signal
import threading
from pathlib import Path

import pytest

from ftcal.cli import main
from ftcal.core import _files
from ftcal.core._files import atomic_output_set


def _contents(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def _simulate(out: Path, seed: int, *extra: str) -> int:
    return main(["simulate", "dataset", "--n-per-sphere", "10", "--n-test", "10", "--seed", str(seed), "--out",
                 str(out), "-q", *extra])


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    """The files of ``simulate dataset`` with seed 1 (the old set) and seed 2 (the new one), written whole."""
    root = tmp_path_factory.mktemp("sets")
    assert _simulate(root / "old", 1) == 0 and _simulate(root / "new", 2) == 0
    old, new = _contents(root / "old"), _contents(root / "new")
    assert old.keys() == new.keys() and all(old[n] != new[n] for n in ("train.csv", "test.csv", "info.json"))
    return old, new


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_between_two_renames_leaves_the_whole_old_or_the_whole_new_set(two_runs, tmp_path, monkeypatch,
                                                                               sig):
    """A real signal sent to the process right after the first file of the set was put in place (``--force`` over
    an older set): the command ends as interrupted, and the folder holds one run's files, not some of each."""
    old, new = two_runs
    out = tmp_path / "out"
    out.mkdir()
    for name, data in old.items():
        (out / name).write_bytes(data)
    real_replace = os.replace
    sent = []

    def replace_then_signal(src, dst, *args, **kwargs):
        real_replace(src, dst, *args, **kwargs)
        if Path(dst).parent == out and not Path(dst).name.startswith(".") and not sent:  # a final name: the commit
            sent.append(dst)
            os.kill(os.getpid(), sig)  # delivered by the OS, handled by ftcal's own signal handler

    monkeypatch.setattr(_files.os, "replace", replace_then_signal)
    # as in a user's terminal: a test runner's worker may have inherited SIGINT ignored (then ftcal rightly keeps
    # ignoring it, and the command ends normally)
    inherited = signal.signal(sig, signal.SIG_DFL if sig != signal.SIGINT else signal.default_int_handler)
    try:
        code = _simulate(out, 2, "--force")
    finally:
        signal.signal(sig, inherited)
    monkeypatch.undo()
    assert sent, "the set was never put in place"
    assert code == 128 + sig
    left = _contents(out)
    assert left in (old, new), {n: (left.get(n) == old.get(n), left.get(n) == new.get(n)) for n in old}


def test_a_failed_rename_in_the_middle_of_a_forced_set_puts_the_old_set_back(tmp_path):
    """``--force`` over an older set: the first file is replaced, the second cannot be (a folder was made in its
    place meanwhile): the first is put back, the old set stands whole and nothing of the run stays."""
    from ftcal.cli._common import OutputPlan

    out = tmp_path / "out"
    out.mkdir()
    (out / "a.model.npz").write_text("old A")
    plan = OutputPlan(out, ["a.model.npz", "b.fit.json"], force=True)
    with pytest.raises(IsADirectoryError, match="as they were"):
        with plan.as_one_set():
            with plan.writing("a.model.npz") as tmp:
                tmp.write_text("new A")
            with plan.writing("b.fit.json") as tmp:
                tmp.write_text("new B")
            (out / "b.fit.json").mkdir()  # made meanwhile (after the plan's checks), by someone else
            (out / "b.fit.json" / "keep").write_text("in the way")
    assert (out / "a.model.npz").read_text() == "old A"
    assert sorted(p.name for p in out.iterdir()) == ["a.model.npz", "b.fit.json"]
    assert (out / "b.fit.json" / "keep").read_text() == "in the way"


def test_a_set_replaces_only_what_it_writes_and_puts_the_old_files_back_if_it_fails(tmp_path):
    for name in ("tool.json", "tool.identification.json"):
        (tmp_path / name).write_text(f"old {name}")
    with atomic_output_set(overwrite=True, error=FileExistsError) as files:
        with files.writing(tmp_path / "tool.json") as tmp:
            tmp.write_text("new tool")
    assert _contents(tmp_path) == {"tool.json": b"new tool", "tool.identification.json": b"old tool.identification.json"}

    (tmp_path / "tool.json").write_text("old tool")
    with pytest.raises(OSError), atomic_output_set(overwrite=True, error=FileExistsError) as files:
        with files.writing(tmp_path / "tool.json") as tmp:
            tmp.write_text("new tool")
        with files.writing(tmp_path / "poses.csv") as tmp:
            tmp.write_text("new poses")
        (tmp_path / "poses.csv").mkdir()  # the rename of the last file fails
    assert _contents(tmp_path) == {"tool.identification.json": b"old tool.identification.json", "tool.json": b"old tool"}


def test_a_set_is_put_in_place_under_the_folders_lock(tmp_path):
    """Another run holding the folder's lock (its own set going in) keeps this set out until it is done."""
    lock = os.open(tmp_path, os.O_RDONLY)
    fcntl.flock(lock, fcntl.LOCK_EX)
    errors = []

    def write_set():
        try:
            with atomic_output_set(overwrite=True, error=FileExistsError) as files:
                for name in ("a.csv", "b.json"):
                    with files.writing(tmp_path / name) as tmp:
                        tmp.write_text("this run")
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)

    worker = threading.Thread(target=write_set)
    try:
        worker.start()
        worker.join(0.5)
        assert worker.is_alive() and not (tmp_path / "a.csv").exists()  # waiting for the lock, nothing in place
    finally:
        os.close(lock)  # releases the lock
        worker.join(60)
    assert not errors and _contents(tmp_path) == {"a.csv": b"this run", "b.json": b"this run"}


def test_identify_load_with_force_and_no_report_keeps_a_file_of_a_report_name_and_says_so(tmp_path, capsys):
    # the user's own tool.identification.json (or an earlier run's: ftcal cannot tell) is not this run's output:
    # --force replaces what the run writes, never removes what it does not
    from ftcal.cli._tool_drift import report_names

    out = tmp_path / "t"
    out.mkdir()
    kept = report_names("tool")
    for name in kept:
        (out / name).write_text(f"my own notes in {name}")
    poses = tmp_path / "poses.csv"
    _write_static_poses(poses)
    assert main(["identify-load", str(poses), "--out", str(out), "--force", "-q"]) == 0
    assert (out / "tool.tool.json").exists()
    assert all((out / name).read_text() == f"my own notes in {name}" for name in kept)
    err = capsys.readouterr().err
    assert all(f"ftcal: warning: {out / name} was kept as it is" in err for name in kept), err


def _write_static_poses(path: Path) -> None:
    """A pose file: a 1.3 kg tool's weight and a bias in the sensor frame at 12 random orientations, no times."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    from ftcal.experiment import ToolLoad

    tool = ToolLoad(mass=1.3, center_of_mass=np.array([0.012, -0.008, 0.065]),
                    bias=np.array([1.5, -2.0, 0.7, 0.05, -0.03, 0.02]))
    R = Rotation.random(12, random_state=4).as_matrix()
    W = tool.gravity_wrench(R) + np.random.default_rng(4).normal(size=(12, 6)) * np.array([0.15] * 3 + [0.006] * 3)
    rows = np.column_stack([Rotation.from_matrix(R).as_quat(), W])
    path.write_text("qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz\n" + "".join(",".join(repr(float(v)) for v in r) + "\n"
                                                            for r in rows))


def test_files_a_library_writes_itself_join_the_set_through_a_private_folder(tmp_path):
    """``simulate experiment`` and ``demo`` call library functions that write their own files: they write into a
    private folder whose planned files join the set; a failure leaves nothing of them, and no folder."""
    from ftcal.cli._common import OutputPlan

    out = tmp_path / "out"
    plan = OutputPlan(out, ["a.csv", "models/b.model.npz"], force=False)
    with pytest.raises(RuntimeError), plan.as_one_set(), plan.staging() as stage:
        (stage / "a.csv").write_text("a")
        raise RuntimeError("the library failed")
    assert not out.exists() or list(out.iterdir()) == []
    with plan.as_one_set():
        with plan.staging() as stage:
            (stage / "a.csv").write_text("a")
            (stage / "models").mkdir()
            (stage / "models" / "b.model.npz").write_text("b")
        assert not (out / "a.csv").exists()  # in place only with the whole set
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == ["a.csv", "models", "models/b.model.npz"]
