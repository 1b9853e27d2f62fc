"""One cell, four programs (issue 14): the Pick-and-Place demos of the robot libraries command the
same six targets (st_src/scenarios/pnp_demo.toml). Each demo runs as `stvm run <project>` would run
it -- its manifest's [demo] scenario, one full PnP cycle -- in lockstep with a fresh emulated TM;
the test compares, against the thesis demo, the sequence of motion commands the robot received
(command IDs, QueueTags and other statements ignored, numbers compared as numbers) and the TCP
path the robot moved (every scan, stationary samples dropped): every point of one path lies within
one emulator step (the largest distance the TCP moves in one scan) of the other path.

PROGRAMS lists the projects; a library with a PnP demo is added with one entry (its project path):
the Schneider IF_RobotMotion library of issue 14 part 4 is `"st_src/schneider"`.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

import stvm
from robotlibs_helpers import PNP_TARGETS, REPO, motion_commands

PROGRAMS = [
    "st_src/PnP_Example.st",        # the thesis demo (V1, restored)
    "st_src/cbt_v2",                # CBT_Commands V2
    "st_src/rockwell",              # raM_Robot_Opr_LoadPath
    "st_src/kuka",                  # mxAutomation style
    "st_src/schneider",             # IF_RobotMotion (issue 14 part 4)
]
REFERENCE = PROGRAMS[0]
MAX_SCANS = 40000


@dataclass
class CellRun:
    project: str
    motions: list = field(default_factory=list)
    path: np.ndarray | None = None          # (n, 6): x, y, z, rx, ry, rz while moving
    moving_scans: int = 0
    cycle_scan: int = 0


def demo_config(project: str) -> tuple[Path, dict]:
    path = REPO / project
    folder = path if path.is_dir() else path.parent
    with (folder / "stvm.toml").open("rb") as fh:
        return folder, tomllib.load(fh)["demo"]


@lru_cache(maxsize=None)
def run_demo(project: str) -> CellRun:
    """One PnP cycle of `project`'s demo in lockstep; the robot's TCP sampled after every scan."""
    from emulator.motion import matrix_to_pose
    from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT, LockstepTransport
    from stvm.scenario import ScenarioDriver, load_scenario
    folder, demo = demo_config(project)
    scenario = load_scenario(folder / demo["scenario"])
    transport = LockstepTransport(latency_scans=1)
    vm = stvm.load([str(REPO / project)]).start(scan="1ms", transport=transport)
    driver = ScenarioDriver(scenario, vm, transport.inject_fault)
    vm.on_scan_end.append(driver.after_scan)
    transport.attach(vm)
    driver.apply_initial({scenario.robot_address: LOCKSTEP_HOST, scenario.robot_port: LOCKSTEP_PORT})
    robot = transport.link.robot
    samples: list = []
    vm.on_scan_end.append(lambda _vm: samples.append(matrix_to_pose(robot.executor.current_tcp())))
    run = CellRun(project)
    previous = None
    try:
        for scan in range(MAX_SCANS):
            vm.scan()
            step = vm.get(demo["step_variable"])
            if previous == demo["cycle_from"] and step == demo["cycle_to"]:
                run.cycle_scan = scan
                break
            previous = step
        else:
            raise AssertionError(f"{project}: no complete PnP cycle in {MAX_SCANS} scans (step {previous})")
    finally:
        vm.close()
    run.motions = motion_commands(f.data for f in transport.frames if f.direction == "rx")
    poses = np.array(samples)
    moving = np.any(np.abs(np.diff(poses, axis=0)) > 1e-9, axis=1)
    run.moving_scans = int(moving.sum())
    run.path = poses[1:][moving]
    return run


def step_of(path: np.ndarray) -> np.ndarray:
    """The largest change per scan of each coordinate along a path (the emulator's step)."""
    return np.abs(np.diff(path, axis=0)).max(axis=0)


def farthest(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per coordinate, how far the points of `a` are from the nearest point of `b` (position
    nearest in xyz; the orientation difference at that point)."""
    worst = np.zeros(6)
    for chunk in np.array_split(a, max(1, len(a) // 500)):
        d = np.linalg.norm(chunk[:, None, :3] - b[None, :, :3], axis=2)
        nearest = b[d.argmin(axis=1)]
        worst = np.maximum(worst, np.abs(chunk - nearest).max(axis=0))
    return worst


@pytest.mark.parametrize("project", PROGRAMS)
def test_demo_completes_one_cycle_over_the_six_targets(project):
    run = run_demo(project)
    assert len(run.motions) == 6, run.motions
    for (name, args), target in zip(run.motions, PNP_TARGETS):
        assert name == "PTP" and args[0] == "CPP"
        assert args[1:7] == pytest.approx(list(target))


@pytest.mark.parametrize("project", PROGRAMS[1:])
def test_same_motion_commands_as_the_thesis_demo(project):
    assert run_demo(project).motions == run_demo(REFERENCE).motions


@pytest.mark.parametrize("project", PROGRAMS[1:])
def test_same_tcp_path_within_one_emulator_step(project):
    ref, other = run_demo(REFERENCE).path, run_demo(project).path
    # + 1e-5 (mm, degrees): orientations carry the inverse kinematics' rounding noise (a few
    # 1e-6 degrees; the IK converges to 0.01 mm / 0.01 degrees), which depends on float details
    tolerance = np.maximum(step_of(ref), step_of(other)) + 1e-5
    assert np.all(farthest(other, ref) <= tolerance), (farthest(other, ref), tolerance)
    assert np.all(farthest(ref, other) <= tolerance), (farthest(ref, other), tolerance)
    # the same motion time: at most one scan per segment apart (the sub-scan start of a motion)
    assert abs(run_demo(project).moving_scans - run_demo(REFERENCE).moving_scans) <= 6
