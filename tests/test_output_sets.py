"""A run's outputs are one set (all or none), and a failed write (a full disk) names the file it was writing."""

from __future__ import annotations

import contextlib
import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from ftcal.core._files import atomic_output, atomic_output_set


def _fill_device(tmp: Path) -> None:
    """Write to ``/dev/full`` as if ``tmp`` were on a full disk: the error of a real write with no file name."""
    tmp.write_text("started")
    with open("/dev/full", "w") as full:
        full.write("x" * 10_000)
        full.flush()


needs_dev_full = pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full on this system")


@needs_dev_full
def test_a_full_disk_names_the_file_being_written_and_leaves_nothing(tmp_path):
    target = tmp_path / "model.npz"
    with pytest.raises(OSError) as caught, atomic_output(target, overwrite=False, error=FileExistsError) as tmp:
        _fill_device(tmp)
    assert caught.value.errno == errno.ENOSPC and caught.value.filename == str(target)
    assert list(tmp_path.iterdir()) == []


@needs_dev_full
@pytest.mark.parametrize("force", [False, True])
def test_an_output_set_is_written_whole_or_not_at_all(tmp_path, force):
    old = {name: f"old {name}" for name in ("a.csv", "b.json", "c.png")}
    if force:
        for name, text in old.items():
            (tmp_path / name).write_text(text)
    with pytest.raises(OSError) as caught, atomic_output_set(overwrite=force, error=FileExistsError) as files:
        for name in ("a.csv", "b.json"):
            with files.writing(tmp_path / name) as tmp:
                tmp.write_text(f"new {name}")
        with files.writing(tmp_path / "c.png") as tmp:
            _fill_device(tmp)
    assert caught.value.filename == str(tmp_path / "c.png")
    left = {p.name: p.read_text() for p in tmp_path.iterdir()}
    assert left == (old if force else {})  # the old set untouched, no temporary file left


def test_a_replaced_set_is_all_new_and_a_set_meeting_another_runs_file_replaces_nothing(tmp_path):
    for name in ("a.csv", "b.json"):
        (tmp_path / name).write_text("old")
    with atomic_output_set(overwrite=True, error=FileExistsError) as files:
        for name in ("a.csv", "b.json"):
            with files.writing(tmp_path / name) as tmp:
                tmp.write_text("new")
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {"a.csv": "new", "b.json": "new"}

    fresh = tmp_path / "fresh"
    fresh.mkdir()
    with pytest.raises(FileExistsError, match="b.json appeared while this run was working"):
        with atomic_output_set(overwrite=False, error=FileExistsError) as files:
            for name in ("a.csv", "b.json"):
                with files.writing(fresh / name) as tmp:
                    tmp.write_text("this run")
            (fresh / "b.json").write_text("another run")  # finished first
    assert (fresh / "b.json").read_text() == "another run"
    assert not (fresh / "a.csv").exists()  # none of the set was put in place
    assert sorted(p.name for p in fresh.iterdir()) == ["b.json", "unplaced.1"]
    # this run's work is kept whole in a sub-folder, as the message says, where the folder's readers do not take it
    # for the other run's files (a run-log or dataset folder is read by its *.csv)
    assert {p.name: p.read_text() for p in (fresh / "unplaced.1").iterdir()} == {"a.csv": "this run",
                                                                                 "b.json": "this run"}


def test_run_logs_of_a_folder_leave_out_temporaries_and_a_lost_race(tmp_path):
    from ftcal.io import run_log_files

    for name in ("config0_load.csv", ".config0_load.k2x9.partial.csv"):
        (tmp_path / name).write_text("")
    (tmp_path / "unplaced.1").mkdir()
    (tmp_path / "unplaced.1" / "config1_load.csv").write_text("")
    assert [p.name for p in run_log_files(tmp_path)] == ["config0_load.csv"]


@contextlib.contextmanager
def _small_disk(path: Path, size: str = "64k"):
    """A tmpfs of ``size`` mounted at ``path`` (root only), unmounted afterwards."""
    path.mkdir()
    proc = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)], capture_output=True)
    if proc.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here (needs root): {proc.stderr.decode().strip()}")
    try:
        yield path
    finally:
        subprocess.run(["umount", str(path)], check=True)


@pytest.mark.skipif(os.geteuid() != 0, reason="mounting a small tmpfs needs root")
@pytest.mark.parametrize("taken", [False, True])
def test_plan_on_a_full_disk_names_the_file_and_leaves_no_part_of_its_outputs(tmp_path, taken):
    with _small_disk(tmp_path / "disk") as disk:
        out = disk / "plan"
        if taken:  # a previous plan stays whole when the new one does not fit (--force)
            out.mkdir()
            for name in ("poses.csv", "plan.json", "coverage.png"):
                (out / name).write_text(f"previous {name}")
        before = sorted(p.name for p in out.iterdir()) if taken else None
        proc = subprocess.run([sys.executable, "-m", "ftcal", "plan", "--robot", "panda", "--subdivisions", "1",
                               "--out", str(out), "-q", *(["--force"] if taken else [])],
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 2, proc.stderr
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("ftcal: error: "), lines
        assert "No space left on device" in lines[0] and f"{out}/" in lines[0]  # names the file
        assert "free" in lines[0]  # and what to do
        if taken:
            assert sorted(p.name for p in out.iterdir()) == before
            assert all(p.read_text() == f"previous {p.name}" for p in out.iterdir())
        else:
            assert not out.exists() or list(out.iterdir()) == []


def test_a_dangling_link_or_a_read_only_file_is_never_replaced_force_or_not(tmp_path, capsys):
    import os
    import stat

    from ftcal.cli import main

    import numpy as np

    rng = np.random.default_rng(0)
    w = rng.normal(size=(60, 6))
    raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6))
    data = tmp_path / "d.csv"
    data.write_text("s0,s1,s2,s3,s4,s5,Fx,Fy,Fz,Tx,Ty,Tz\n" + "".join(
        ",".join(f"{v:.6f}" for v in row) + "\n" for row in np.hstack([raw, w])))
    out = tmp_path / "o"
    out.mkdir()
    (out / "linear.model.npz").symlink_to(tmp_path / "elsewhere" / "my.model.npz")  # the user's link, dangling
    assert main(["fit", str(data), "--model", "linear", "--out", str(out), "--force", "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is a symbolic link to" in err[0] and "does not exist" in err[0], err
    assert (out / "linear.model.npz").is_symlink()
    (out / "linear.model.npz").unlink()
    (out / "linear.model.npz").write_text("my protected notes")
    os.chmod(out / "linear.model.npz", stat.S_IRUSR | stat.S_IRGRP)
    assert main(["fit", str(data), "--model", "linear", "--out", str(out), "--force", "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is read-only (write-protected)" in err[0], err
    assert (out / "linear.model.npz").read_text() == "my protected notes"
