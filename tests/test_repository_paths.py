"""The repository works from any checkout: no tracked file names a path of the machine it was
written on (the checkout's own folder, the folder that holds it, or the home folder)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from twil_control import PACKAGE_ROOT

# folders never searched when the checkout is not a git repository (an unpacked archive)
UNTRACKED = {".git", ".venv", "runs", "build", "__pycache__", ".pytest_cache", "artifacts"}
THIS_FILE = Path(__file__).resolve()
# top-level folders every machine has: a checkout's parent that is one of them ("/tmp/house" in
# an example) is too common a prefix to be this machine's
SHARED_FOLDERS = {"/", "/tmp", "/var", "/home", "/usr", "/opt", "/srv", "/mnt"}


def tracked_files(root: Path) -> list[Path]:
    """The files git tracks under root; every file but the build folders outside a git checkout."""
    try:
        out = subprocess.run(["git", "ls-files", "-z"], cwd=root, capture_output=True, check=True).stdout
        return [root / name for name in out.decode().split("\0") if name]
    except (OSError, subprocess.CalledProcessError):
        return [
            p
            for p in root.rglob("*")
            if p.is_file()
            and not UNTRACKED & set(p.relative_to(root).parts)
            and not p.name.endswith(".egg-info")
        ]


def machine_paths(root: Path) -> list[str]:
    """Absolute paths that exist only on this machine: the checkout, its parent folder (unless
    it is a folder every machine has) and the home folder, each as a prefix with its slash."""
    candidates = {str(root)}
    if str(root.parent) not in SHARED_FOLDERS:
        candidates.add(str(root.parent) + os.sep)
    home = Path.home()
    if str(home) not in SHARED_FOLDERS:
        candidates.add(str(home) + os.sep)
    return sorted(candidates)


def test_no_tracked_file_names_an_absolute_path_of_this_machine():
    files = [f for f in tracked_files(PACKAGE_ROOT) if f.resolve() != THIS_FILE and f.is_file()]
    assert len(files) > 100, f"only {len(files)} files found under {PACKAGE_ROOT}"
    needles = [p.encode() for p in machine_paths(PACKAGE_ROOT)]
    assert str(PACKAGE_ROOT).encode() in needles
    leaks = [
        f"{f.relative_to(PACKAGE_ROOT)}: {n.decode()}" for f in files for n in needles if n in f.read_bytes()
    ]
    assert not leaks, "tracked files name paths of this machine:\n" + "\n".join(leaks)


def test_the_check_finds_a_path_it_must_refuse(tmp_path):
    root = tmp_path / "checkout" / "twil_control"
    root.mkdir(parents=True)
    needles = machine_paths(root)
    assert str(root) in needles and str(root.parent) + os.sep in needles
    # a leak written the way a test or bench would write it is caught
    line = f'DATA = Path("{root.parent}/data/carmen")'.encode()
    assert any(n.encode() in line for n in needles)
    # a checkout directly in a development folder of its own: that folder is this machine's
    assert str(Path("/src")) + os.sep in machine_paths(Path("/src/twil_control"))
    # an example path under /tmp in the docs is not this machine's
    assert not any(n.encode() in b"-o /tmp/house" for n in machine_paths(Path("/tmp/y")))
