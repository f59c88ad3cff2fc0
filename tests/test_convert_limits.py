"""A user's xacro or mesh cannot take the machine (core/limited.py): xacro and mesh conversion run
in a child process under a memory (RLIMIT_AS) and time limit, and going past one is one error
naming the file and the option that raises it. Meshes: size limits in bytes and triangles,
zero-area triangles dropped, nothing left in the cache by a failed conversion.

Each scenario that could grow without bound runs inside a guard process of its own (RLIMIT_AS
3 GB, 60 CPU seconds), so that code without the limits fails the test instead of exhausting the
test machine.
"""

from __future__ import annotations

import json
import os
import resource
import struct
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from twil_control.core import limited
from twil_control.description import meshes
from twil_control.description.drake_urdf import urdf_for_drake
from twil_control.description.urdf import DescriptionError, parse_urdf

GUARD_MEMORY = 3 << 30
GUARD_SECONDS = 60


def guarded(code: str, env: dict | None = None) -> dict:
    """Run `code` (which prints one JSON line last) in a guarded process; its JSON, or how it died."""

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (GUARD_MEMORY, GUARD_MEMORY))
        resource.setrlimit(resource.RLIMIT_CPU, (GUARD_SECONDS, GUARD_SECONDS + 1))

    proc = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        preexec_fn=limit,
        timeout=GUARD_SECONDS * 5,
        env={**os.environ, **(env or {})},
    )
    lines = proc.stdout.strip().splitlines()
    if proc.returncode != 0 or not lines:
        return {"died": proc.returncode, "stderr": proc.stderr[-2000:]}
    return json.loads(lines[-1])


XACRO_RUN = """
    import json, sys
    from twil_control.core import limited
    from twil_control.description.xacro_command import run_xacro
    limited.LIMITS = limited.Limits(memory={memory}, seconds={seconds})
    try:
        run_xacro([{path!r}])
        print(json.dumps({{"ok": True}}))
    except Exception as error:
        print(json.dumps({{"error": type(error).__name__, "text": str(error),
                           "limit": isinstance(error, limited.LimitError)}}))
"""


def _xacro(tmp_path, body: str) -> str:
    path = tmp_path / "big.urdf.xacro"
    path.write_text(
        f'<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r">\n{body}\n<link name="base"/>\n</robot>\n'
    )
    return str(path)


def test_a_xacro_property_doubled_into_gigabytes_stops_at_the_memory_limit(tmp_path):
    doubled = [f'<xacro:property name="p0" value="{"abcdefghij" * 1000}"/>'] + [
        f'<xacro:property name="p{i}" value="${{p{i - 1}+p{i - 1}}}"/>' for i in range(1, 21)
    ]  # p20 is 10 GB
    path = _xacro(tmp_path, "\n".join(doubled) + '\n<link name="${p20}"/>')
    got = guarded(XACRO_RUN.format(memory=128 << 20, seconds=150, path=path))  # memory first, even loaded
    assert got.get("limit") is True, got
    assert got["text"].startswith(f"xacro {path}: needed more than 128M of memory")
    assert "--convert-memory" in got["text"] and "\n" not in got["text"]


def test_a_xacro_expression_that_computes_for_minutes_stops_at_the_time_limit(tmp_path):
    path = _xacro(tmp_path, '<xacro:property name="n" value="${10**10**8}"/>\n<link name="l${n}"/>')
    got = guarded(XACRO_RUN.format(memory=1 << 30, seconds=2, path=path))
    assert got.get("limit") is True, got
    assert got["text"] == (
        f"xacro {path}: took more than 2 s, the limit of the child process that reads it; raise it "
        "with --convert-time SECONDS"
    )


def test_a_xacro_within_the_limits_is_processed_in_the_child(tmp_path):
    path = _xacro(tmp_path, '<xacro:property name="w" value="${0.5 * 2}"/>\n<link name="wheel_${w}"/>')
    from twil_control.description.xacro_command import run_xacro

    assert '<link name="wheel_1.0"/>' in run_xacro([path])


# -- meshes ------------------------------------------------------------------------------------
def binary_stl(path, triangles: np.ndarray) -> None:
    """A binary STL of (n, 3, 3) vertices."""
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + struct.pack("<I", len(triangles)))
        for tri in triangles:
            f.write(struct.pack("<12fH", 0, 0, 0, *tri.reshape(-1), 0))


def grid_triangles(n: int) -> np.ndarray:
    """n triangles of area 0.5 cm^2 side by side, none sharing all three corners."""
    i = np.arange(n, dtype=np.float64)[:, None]
    a = np.hstack([i * 0.02, np.zeros((n, 2))])
    return np.stack([a, a + [0.01, 0, 0], a + [0, 0.01, 0]], axis=1)


URDF = """<robot name="r"><link name="base_link"><visual><geometry>
<mesh filename="{mesh}"/></geometry></visual></link></robot>"""


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("TWIL_MESH_CACHE", str(folder))
    monkeypatch.setattr(limited, "LIMITS", limited.Limits(memory=1 << 30, seconds=60))
    return folder


def _convert(path):
    return urdf_for_drake(parse_urdf(URDF.format(mesh=path), "r.urdf"), "r", None)


def test_zero_area_triangles_are_dropped_and_a_mesh_of_them_only_is_refused(tmp_path, cache):
    good, flat = grid_triangles(300), np.repeat(grid_triangles(200)[:, :1], 3, axis=1)
    binary_stl(tmp_path / "mixed.stl", np.concatenate([good, flat]))
    obj = meshes.convert(tmp_path / "mixed.stl")
    assert sum(line.startswith("f ") for line in obj.read_text().splitlines()) == 300
    binary_stl(tmp_path / "flat.stl", flat)
    with pytest.raises(DescriptionError) as error:
        _convert(tmp_path / "flat.stl")
    assert "link 'base_link' visual mesh" in str(error.value) and "no triangles of non-zero area" in str(
        error.value
    )
    assert [p.name for p in cache.iterdir()] == [obj.name]  # nothing kept of the failed one


def test_a_mesh_over_the_triangle_or_byte_limit_is_refused_naming_mesh_and_link(tmp_path, cache, monkeypatch):
    binary_stl(tmp_path / "many.stl", grid_triangles(1200))
    monkeypatch.setattr(limited, "LIMITS", limited.Limits(mesh_triangles=1000))
    with pytest.raises(DescriptionError) as error:
        _convert(tmp_path / "many.stl")
    text = str(error.value)
    assert "link 'base_link'" in text and "1200 triangles are more than the 1000 allowed" in text
    assert "--max-mesh-triangles" in text
    monkeypatch.setattr(limited, "LIMITS", limited.Limits(mesh_bytes=50_000))
    with pytest.raises(
        DescriptionError, match=r"link 'base_link'.*0\.1 MiB is more than the 50000 bytes.*--max-mesh-size"
    ):
        _convert(tmp_path / "many.stl")
    assert not cache.exists() or list(cache.iterdir()) == []


def test_random_bytes_named_stl_are_one_error_not_a_missing_module(tmp_path, cache):
    (tmp_path / "noise.stl").write_bytes(np.random.default_rng(0).bytes(1 << 20))
    with pytest.raises(DescriptionError) as error:
        _convert(tmp_path / "noise.stl")
    assert "noise.stl" in str(error.value) and "ModuleNotFoundError" not in str(error.value)
    assert list(cache.iterdir()) == []


def test_a_mesh_conversion_past_the_memory_limit_leaves_nothing_in_the_cache(tmp_path):
    binary_stl(tmp_path / "big.stl", grid_triangles(400_000))  # 20 MB, ~1 GB once trimesh has it
    got = guarded(
        f"""
        import json
        from pathlib import Path
        from twil_control.core import limited
        from twil_control.description import meshes
        limited.LIMITS = limited.Limits(memory=300 << 20, seconds=60)
        try:
            meshes.convert(Path({str(tmp_path / "big.stl")!r}))
            print(json.dumps({{"ok": True}}))
        except Exception as error:
            print(json.dumps({{"text": str(error), "limit": isinstance(error, limited.LimitError)}}))
        """,
        env={"TWIL_MESH_CACHE": str(tmp_path / "cache")},
    )
    assert got.get("limit") is True, got
    assert got["text"].startswith(f"mesh {tmp_path / 'big.stl'}: needed more than 300M of memory")
    assert list((tmp_path / "cache").iterdir()) == []
