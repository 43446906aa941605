"""The output rule (pendulum_lqg.util.files): a written file is replaced whole or not at all, and
only a new path or a regular file is ever replaced (issue 45, item 1)."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.files import atomic_write, regular_target, replacing, save_figure

OLD = b"\x89PNG old picture " + bytes(range(256)) * 40


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_replacing_a_writer_that_fails_midway_keeps_the_old_file_whole(tmp_path):
    out = tmp_path / "picture.png"
    out.write_bytes(OLD)
    with pytest.raises(OSError, match="No space left") as err:
        with replacing(out, where="--plot", what="picture") as tmp:
            tmp.write_bytes(b"half a new picture")
            raise OSError(28, "No space left on device")
    assert err.value.filename == str(out)      # named after the user's file, not the temporary one
    assert out.read_bytes() == OLD
    assert _leftovers(tmp_path) == []           # the temporary file is removed


def test_replacing_a_writer_interrupted_by_ctrl_c_keeps_the_old_file_whole(tmp_path):
    out = tmp_path / "score.json"
    out.write_bytes(OLD)
    with pytest.raises(KeyboardInterrupt), replacing(out) as tmp:
        tmp.write_bytes(b"{")
        raise KeyboardInterrupt
    assert out.read_bytes() == OLD
    assert _leftovers(tmp_path) == []


def test_replacing_replaces_the_file_once_the_block_ends(tmp_path):
    out = tmp_path / "board.md"
    out.write_bytes(OLD)
    inode = os.stat(out).st_ino
    with replacing(out) as tmp:
        assert tmp.parent == tmp_path and tmp.name.startswith(".board.md.")
        assert tmp.name.endswith(".tmp")        # matched by no *.md / *.csv / *.json glob
        tmp.write_text("| new |\n")
        assert out.read_bytes() == OLD          # untouched until the rename
    assert out.read_text() == "| new |\n"
    assert os.stat(out).st_ino != inode         # a new file renamed over, not rewritten in place
    assert _leftovers(tmp_path) == []


def test_a_symlink_to_a_regular_file_is_followed_and_kept(tmp_path):
    real = tmp_path / "real.json"
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    atomic_write(link, "new")
    assert link.is_symlink() and real.read_text() == "new"


def _special(tmp_path: Path, kind: str) -> Path:
    target = tmp_path / f"target-{kind.replace(' ', '-')}"
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "folder":
        target.mkdir()
    elif kind == "symlink loop":
        target.symlink_to(target.name)
    elif kind == "symlink chain loop":
        (tmp_path / "a").symlink_to("b")
        (tmp_path / "b").symlink_to("a")
        target = tmp_path / "a"
    elif kind == "char device":
        if os.geteuid() != 0:
            pytest.skip("mknod of a character device needs root")
        os.mknod(target, stat.S_IFCHR | 0o666, os.makedev(1, 3))     # what /dev/null is
    return target


@pytest.mark.parametrize(("kind", "says"), [
    ("fifo", "is a FIFO (named pipe)"), ("folder", "is a folder"),
    ("char device", "is a character device"),
    ("symlink loop", "is a symbolic link that loops"),
    ("symlink chain loop", "is a symbolic link that loops"),
])
def test_replacing_refuses_what_is_not_a_regular_file_and_leaves_it(tmp_path, kind, says):
    target = _special(tmp_path, kind)
    before = os.lstat(target)
    with pytest.raises(ConfigError) as err, replacing(target, where="--plot", what="picture"):
        pytest.fail("the block must not run")
    text = str(err.value)
    assert text.startswith(f"--plot: {target} {says}") and "\n" not in text, text
    assert text.endswith("expected a regular file or a new path for the picture (it is left as "
                         "it is)")
    after = os.lstat(target)
    assert (after.st_mode, after.st_ino) == (before.st_mode, before.st_ino)
    assert [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


def test_regular_target_in_a_looping_folder_is_one_line(tmp_path):
    (tmp_path / "loop").symlink_to("loop")
    with pytest.raises(ConfigError, match=r"^out: .*loop/x\.png is a symbolic link that loops"):
        regular_target("out", tmp_path / "loop" / "x.png")


class HalfWriter:
    """A figure whose ``savefig`` writes part of a picture and then fails (a full disk)."""

    def savefig(self, fname, *, format=None, **options):
        Path(fname).write_bytes(b"\x89PNG half")
        raise OSError(28, "No space left on device")


def test_save_figure_failed_write_keeps_the_old_picture(tmp_path):
    out = tmp_path / "episode.png"
    out.write_bytes(OLD)
    with pytest.raises(OSError, match="No space left"):
        save_figure(HalfWriter(), out, where="--plot")
    assert out.read_bytes() == OLD and _leftovers(tmp_path) == []


@pytest.mark.parametrize(("suffix", "magic"), [(".png", b"\x89PNG"), (".svg", b"<?xml"),
                                               (".pdf", b"%PDF")])
def test_save_figure_writes_the_format_of_the_suffix(tmp_path, suffix, magic):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 1))
    fig.subplots().plot([0, 1], [1, 0])
    out = save_figure(fig, tmp_path / f"f{suffix}", dpi=50)
    assert out == tmp_path / f"f{suffix}" and out.read_bytes().startswith(magic)
    assert _leftovers(tmp_path) == []


@pytest.mark.parametrize(("kind", "says"), [("file", "is a regular file"),
                                            ("fifo", "is a FIFO (named pipe)"),
                                            ("loop", "is a symbolic link that loops")])
def test_output_folder_refuses_what_is_not_a_folder(tmp_path, kind, says):
    from pendulum_lqg.util.files import output_folder

    target = tmp_path / "out"
    if kind == "file":
        target.write_text("kept")
    elif kind == "fifo":
        os.mkfifo(target)
    else:
        target.symlink_to("out")
    with pytest.raises(ConfigError) as err:
        output_folder("--out", target, what="scores")
    assert str(err.value).startswith(f"--out: {target} {says}; expected a folder for the scores")
    assert output_folder("--out", tmp_path / "new" / "deep", what="scores").is_dir()


def test_item02_remove_entry_removes_a_link_never_its_target(tmp_path):
    """Issue 55 item 2: ``--force``'s one rule (``bench``'s results folder, ``train``'s run
    files): a link to a file or to a folder is removed as a link, and a folder's tree is removed
    without following the links inside it."""
    from pendulum_lqg.util.files import remove_entry

    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "model.json").write_text("committed")
    out = tmp_path / "out"
    (out / "units").mkdir(parents=True)
    (out / "file-link.json").symlink_to(outside / "model.json")
    (out / "folder-link").symlink_to(outside, target_is_directory=True)
    (out / "units" / "inner-link").symlink_to(outside, target_is_directory=True)
    for name in ("file-link.json", "folder-link", "units", "absent"):
        remove_entry(out / name)
    assert list(out.iterdir()) == []
    assert (outside / "model.json").read_text() == "committed"
