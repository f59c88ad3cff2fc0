"""The runs of a sweep: each one launch with its args, identified by a hash of what it runs.

A run's identity is the hash of the launch file (as named relative to the package root), its
launch args as the command line passes them, its --duration and its --seed: the things that
decide its bag (the same launch, args and seed give the same bag, message for message). Two
sweeps that share a run share its result, and rerunning a sweep finds its finished runs by
these identities.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

from twil_control.core.yaml_io import display_path

from .spec import Scalar, Sweep


@dataclass(frozen=True)
class Run:
    index: int  # position in the sweep (table order)
    run_id: str  # hash of launch + args + duration + seed
    launch: str  # absolute path of the launch file
    args: dict[str, Scalar]  # launch args (fixed and varied), typed as in the sweep file
    varied: dict[str, Scalar]  # the varied values of this run (launch args, duration, seed)
    duration: float | None
    seed: int

    @property
    def name(self) -> str:
        return f"run_{self.run_id}"

    def launch_argv(self) -> list[str]:
        """``name:=value`` tokens, then --duration and --seed, as the launch CLI takes them."""
        argv = [f"{name}:={arg_text(value)}" for name, value in self.args.items()]
        if self.duration is not None:
            argv += ["--duration", arg_text(self.duration)]
        return argv + ["--seed", str(self.seed)]


def arg_text(value: Scalar) -> str:
    """A value as the command line writes it (floats round-trip exactly; YAML booleans)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def run_id(launch: str, args: dict[str, Scalar], duration: float | None, seed: int) -> str:
    identity = {
        "launch": display_path(launch),
        "args": {name: arg_text(args[name]) for name in sorted(args)},
        "duration": None if duration is None else arg_text(float(duration)),
        "seed": int(seed),
    }
    digest = hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()
    return digest[:12]


def runs_of(sweep: Sweep) -> tuple[list[Run], int]:
    """The distinct runs of a sweep in file order, and how many duplicates were merged."""
    runs: list[Run] = []
    seen: set[str] = set()
    duplicates = 0
    for point in sweep.points:
        args = dict(sweep.fixed)
        args.update({k: v for k, v in point.items() if k not in ("duration", "seed")})
        duration = point.get("duration", sweep.duration)
        seed = point.get("seed", sweep.seed)
        ident = run_id(str(sweep.launch), args, duration, seed)
        if ident in seen:  # e.g. random choices drawing the same values twice
            duplicates += 1
            continue
        seen.add(ident)
        runs.append(
            Run(
                index=len(runs),
                run_id=ident,
                launch=str(sweep.launch),
                args=args,
                varied=dict(point),
                duration=duration,
                seed=seed,
            )
        )
    return runs, duplicates
