"""Motion model: kinematics, trapezoidal timing, blending and the FIFO motion queue (spec §8).

Pure and deterministic: time is an integer count of nanoseconds of *motion time*, which the robot
advances only while the project is not paused (spec §8 Pause: the motion holds, the queue is kept,
and Resume completes the interrupted motion).

Timing model (spec §8 [U], §11 #11; every constant is an :class:`EmulatorSettings` field):

* Trapezoid over a distance ``D`` with top speed ``v`` and acceleration time ``ta`` (the TM
  ``accel_ms``: time from rest to top speed): if ``D >= v*ta`` the duration is ``D/v + ta``,
  otherwise the profile is a triangle of duration ``2*sqrt(D*ta/v)``.
* PTP (``JPP``/``CPP``): joint space; each joint's top speed is ``speed% * max_joint_speed``; all
  joints are synchronised to the slowest one.  ``CPP`` targets are converted with inverse kinematics.
* Line/Circle/PLine: Cartesian; path length (line or arc) at ``speed% * max_tcp_speed`` (``P``
  formats) or the given mm/s (``A``/``D``), and the orientation change at the same fraction of
  ``max_tcp_rot_speed``; the slower of the two sets the duration.
* Blending ``b`` % (or a radius): the motion hands over to the next queued motion when
  ``b% * ta_decel`` remains, so the deceleration and the next acceleration overlap; the pose is the
  superposition of both.  A tag queued right after a blended motion is reached at the hand-over.
  If nothing is queued at the hand-over instant the motion stops at its target.
* Precise positioning (``disablePrecise`` false) adds ``precise_settle_ms`` at the end.
* Every duration is multiplied by ``time_scale`` and rounded to whole nanoseconds.

Machine independence (issue 17): the kinematics use :mod:`emulator.detmath` (no BLAS, LAPACK or
C-library trigonometry, whose results differ between CPUs), and the timing model works on exact
rationals: a segment's duration, acceleration, blend and settle times are the integer
nanoseconds nearest to the exact values of the formulas above (ties to even), computed with
``fractions.Fraction`` and ``math.isqrt`` from the (deterministic) distances and the script's
numbers. :class:`SegmentTiming` keeps those inputs, so a test recomputes every time stamp with
an independent reference.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable, Sequence

import numpy as np

from . import detmath as dm
from .settings import DEFAULT_SETTINGS, EmulatorSettings

NS_PER_S = 1_000_000_000
NS_PER_MS = 1_000_000

# --------------------------------------------------------------------------- rotations


def euler_to_matrix(rx: float, ry: float, rz: float) -> np.ndarray:
    """TM orientation (degrees): fixed X-Y-Z angles, R = Rz @ Ry @ Rx."""
    a, b, c = dm.radians(rx), dm.radians(ry), dm.radians(rz)
    ca, sa, cb, sb, cc, sc = dm.cos(a), dm.sin(a), dm.cos(b), dm.sin(b), dm.cos(c), dm.sin(c)
    return np.array([
        [cc * cb, cc * sb * sa - sc * ca, cc * sb * ca + sc * sa],
        [sc * cb, sc * sb * sa + cc * ca, sc * sb * ca - cc * sa],
        [-sb, cb * sa, cb * ca],
    ])


def matrix_to_euler(rot: np.ndarray) -> np.ndarray:
    sy = -float(rot[2, 0])
    ry = dm.asin(max(-1.0, min(1.0, sy)))
    if abs(sy) < 1.0 - 1e-9:
        rx = dm.atan2(rot[2, 1], rot[2, 2])
        rz = dm.atan2(rot[1, 0], rot[0, 0])
    else:  # gimbal lock: put everything into rz
        rx = 0.0
        rz = dm.atan2(-rot[0, 1], rot[1, 1])
    return np.array([dm.degrees(rx), dm.degrees(ry), dm.degrees(rz)])


def pose_to_matrix(pose: Sequence[float]) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = euler_to_matrix(pose[3], pose[4], pose[5])
    out[:3, 3] = pose[:3]
    return out


def matrix_to_pose(mat: np.ndarray) -> np.ndarray:
    return np.concatenate([mat[:3, 3], matrix_to_euler(mat[:3, :3])])


def rotation_angle_deg(r_a: np.ndarray, r_b: np.ndarray) -> float:
    """Angle of the rotation taking ``r_a`` to ``r_b``."""
    # trace(r_a^T r_b) = sum of the elementwise products, in a fixed order
    cos_angle = (dm.dot(np.asarray(r_a).ravel(), np.asarray(r_b).ravel()) - 1.0) / 2.0
    return dm.degrees(dm.acos(max(-1.0, min(1.0, cos_angle))))


def _quat_from_matrix(rot: np.ndarray) -> np.ndarray:
    w = math.sqrt(max(0.0, 1.0 + rot[0, 0] + rot[1, 1] + rot[2, 2])) / 2.0
    x = math.sqrt(max(0.0, 1.0 + rot[0, 0] - rot[1, 1] - rot[2, 2])) / 2.0
    y = math.sqrt(max(0.0, 1.0 - rot[0, 0] + rot[1, 1] - rot[2, 2])) / 2.0
    z = math.sqrt(max(0.0, 1.0 - rot[0, 0] - rot[1, 1] + rot[2, 2])) / 2.0
    x = math.copysign(x, rot[2, 1] - rot[1, 2])
    y = math.copysign(y, rot[0, 2] - rot[2, 0])
    z = math.copysign(z, rot[1, 0] - rot[0, 1])
    return np.array([w, x, y, z])


def _matrix_from_quat(q: np.ndarray) -> np.ndarray:
    w, x, y, z = (float(v) for v in q / dm.norm(q))
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def slerp_matrix(r_a: np.ndarray, r_b: np.ndarray, s: float) -> np.ndarray:
    qa, qb = _quat_from_matrix(r_a), _quat_from_matrix(r_b)
    dot = dm.dot(qa, qb)
    if dot < 0:
        qb, dot = -qb, -dot
    if dot > 0.9995:
        return _matrix_from_quat(qa + s * (qb - qa))
    theta = dm.acos(dot)
    return _matrix_from_quat((dm.sin((1 - s) * theta) * qa + dm.sin(s * theta) * qb) / dm.sin(theta))


# --------------------------------------------------------------------------- kinematics

# Standard DH of a TM5-700 (alpha deg, a mm, d mm, theta offset deg).  Home (0,0,90,0,90,0) gives
# the flange pose (417.5, -122.3, 360.9, 180, 0, 90).
TM5_700_DH = ((-90.0, 0.0, 145.1, 0.0), (0.0, 329.0, 0.0, -90.0), (0.0, 311.5, 0.0, 0.0),
              (90.0, 0.0, -122.3, 90.0), (90.0, 0.0, 106.0, 0.0), (0.0, 0.0, 113.2, 0.0))


# Kinematics results kept per arm model: (DH table bytes, joint limit bytes) -> (ik results, fk
# results), each bounded by `_KEPT_RESULTS` entries (cleared when full)
_RESULTS_BY_MODEL: dict[tuple[bytes, bytes], tuple[dict, dict]] = {}
_KEPT_RESULTS = 512
# PTP timings by their exact inputs and the settings object (kept in the entry, compared with
# `is`): shared by the planners of every robot, bounded as above
_JOINT_TIMINGS: dict[tuple, tuple] = {}


class Kinematics:
    """Forward kinematics by DH and damped-least-squares inverse kinematics (numpy)."""

    def __init__(self, settings: EmulatorSettings = DEFAULT_SETTINGS, dh: Sequence[Sequence[float]] = TM5_700_DH):
        self.dh = np.array(dh, dtype=float)
        self.limits = np.array(settings.joint_limits_deg, dtype=float)
        # per link: alpha, a, d, theta offset and the (constant) cos/sin of alpha
        self._links = [(float(al), float(a), float(d), float(off), dm.cos(dm.radians(al)), dm.sin(dm.radians(al)))
                       for al, a, d, off in dh]
        # (link index, joint angle) -> that link's rows: the pure-Python trigonometry of detmath
        # is most of an fk, and a Jacobian's six fks differ from the base in one joint each
        self._link_rows: dict[tuple[int, float], tuple] = {}
        # `ik` and `fk` results (see there), shared by every arm of the same model (DH table and
        # joint limits): the robots of a cell are identical arms, often on identical paths
        self._ik_results, self._fk_results = _RESULTS_BY_MODEL.setdefault(
            (self.dh.tobytes(), self.limits.tobytes()), ({}, {}))

    def fk(self, joints_deg: Sequence[float], tool: np.ndarray | None = None) -> np.ndarray:
        """4x4 pose of the TCP in the robot base (``tool`` = flange -> TCP transform).

        Kept by the exact bytes of the arguments, as `ik`: a motion is planned twice (the dry
        run, then the run) and a cycle repeats its targets."""
        joints, tool_array = np.asarray(joints_deg), None if tool is None else np.asarray(tool)
        key = (joints.dtype.str, joints.shape, joints.tobytes(),
               None if tool_array is None else (tool_array.dtype.str, tool_array.shape, tool_array.tobytes()))
        found = self._fk_results.get(key) if joints.dtype.kind in "fiu" else None
        if found is None:
            result = np.array(self._chain(joints_deg) + [[0.0, 0.0, 0.0, 1.0]])
            found = dm.matmul(result, tool) if tool is not None else result
            if joints.dtype.kind in "fiu" and (tool_array is None or tool_array.dtype.kind in "fiu"):
                if len(self._fk_results) >= _KEPT_RESULTS:
                    self._fk_results.clear()
                self._fk_results[key] = found
        return found.copy()

    _IDENTITY_ROWS = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]

    def _link(self, index: int, q: float) -> tuple:
        """The first three rows of link `index`'s DH transform at joint angle `q` (degrees)."""
        key = (index, q)
        rows = self._link_rows.get(key) if q != 0.0 else None   # (-0.0 == 0.0: not cached)
        if rows is None:
            alpha, a, d, offset, ca, sa = self._links[index]
            st, ct = dm.sincos(dm.radians(q + offset))
            rows = ((ct, -st * ca, st * sa, a * ct), (st, ct * ca, -ct * sa, a * st), (0.0, sa, ca, d))
            if q != 0.0:
                if len(self._link_rows) >= 256:   # bounded small: the reuse is within one step (the Jacobian), a run visits ever new angles
                    self._link_rows.clear()
                self._link_rows[key] = rows
        return rows

    def _chain(self, joints_deg: Sequence[float], start: int = 0, out: list | None = None,
               prefixes: list | None = None) -> list:
        """The product of the links `start`.. (three rows), multiplied onto `out` (the product of
        the links before `start`; default the identity) in the same order as always, so a chain
        resumed from a prefix gives the same bits as one from the base. `prefixes` collects the
        product after each link."""
        if out is None:
            out = self._IDENTITY_ROWS
        for index in range(start, min(len(self._links), len(joints_deg))):
            (a0, a1, a2, a3), (b0, b1, b2, b3), (c0, c1, c2, c3) = self._link(index, float(joints_deg[index]))
            # out = out @ link, row by row; the implicit last rows are (0, 0, 0, 1): each sum in
            # the order r0*a + r1*b + r2*c + (r3 in the last column, else 0.0), written out
            out = [[r0 * a0 + r1 * b0 + r2 * c0 + 0.0, r0 * a1 + r1 * b1 + r2 * c1 + 0.0,
                    r0 * a2 + r1 * b2 + r2 * c2 + 0.0, r0 * a3 + r1 * b3 + r2 * c3 + r3]
                   for r0, r1, r2, r3 in out]
            if prefixes is not None:
                prefixes.append(out)
        return out

    def within_limits(self, joints_deg: Sequence[float]) -> bool:
        q = np.asarray(joints_deg)
        return bool(np.all(q >= self.limits[:, 0] - 1e-9) and np.all(q <= self.limits[:, 1] + 1e-9))

    def ik(self, target: np.ndarray, seed_deg: Sequence[float], tool: np.ndarray | None = None,
           max_iterations: int = 100) -> np.ndarray | None:
        """Joint angles (deg) whose TCP pose is ``target`` (4x4, robot base), starting from
        ``seed_deg``; None if it does not converge within 0.01 mm / 0.01 deg or leaves the joint
        limits (the target is then unreachable).

        A pure function of its arguments (and the arm's constants), so its results are kept by
        the exact bytes of the arguments: a cycle that repeats its motions (a PnP loop) solves
        each target once, with the same bits every time."""
        seed_array, target_array = np.asarray(seed_deg), np.asarray(target)
        key = (target_array.dtype.str, target_array.shape, target_array.tobytes(), seed_array.dtype.str,
               seed_array.shape, seed_array.tobytes(), None if tool is None else np.asarray(tool).tobytes(),
               max_iterations)
        if key in self._ik_results:
            found = self._ik_results[key]
            return None if found is None else found.copy()
        found = self._ik(target, seed_deg, tool, max_iterations)
        if len(self._ik_results) >= _KEPT_RESULTS:   # bounded: a cycle repeats a few targets; a long run with ever new ones stays small
            self._ik_results.clear()
        self._ik_results[key] = None if found is None else found.copy()
        return found

    def _ik(self, target: np.ndarray, seed_deg: Sequence[float], tool: np.ndarray | None,
            max_iterations: int) -> np.ndarray | None:
        """`_ik_arrays` on plain lists of floats: the same operations in the same order (so the
        same bits), without a numpy call per small step (a solve took ~2 ms, most of it numpy's
        per-call cost on 3- to 6-element arrays). Anything but 4x4 poses takes `_ik_arrays`."""
        target_rows = np.asarray(target, dtype=float).tolist()
        tool_rows = None if tool is None else np.asarray(tool, dtype=float).tolist()
        seed = np.asarray(seed_deg, dtype=float)
        if np.shape(target) != (4, 4) or (tool is not None and np.shape(tool) != (4, 4)) or seed.ndim != 1 \
                or len(seed) != len(self._links):
            return self._ik_arrays(target, seed_deg, tool, max_iterations)
        rad, deg = dm.RAD_PER_DEG, dm.DEG_PER_RAD
        q = [v * rad for v in seed.tolist()]
        position_tolerance, angle_tolerance = 1e-2, dm.radians(1e-2)
        dot, solve = dm._dot_floats, dm.solve_lists
        norm = math.sqrt
        for _ in range(max_iterations):
            q_deg = [v * deg for v in q]
            # the TCP pose at q: the pose error's and the Jacobian's base (one chain for both)
            prefixes = [self._IDENTITY_ROWS]
            pose = self._chain(q_deg, prefixes=prefixes) + [[0.0, 0.0, 0.0, 1.0]]
            if tool_rows is not None:
                pose = self._times_rows(pose, tool_rows)
            err = self._pose_error_rows(target_rows, pose)
            if norm(dot(err[:3], err[:3])) < position_tolerance and norm(dot(err[3:], err[3:])) < angle_tolerance:
                result = np.array(q) * deg
                # Keep angles near the seed (joints rotate more than 360 deg on a TM).
                result = np.asarray(seed_deg) + (result - np.asarray(seed_deg) + 180.0) % 360.0 - 180.0
                return result if self.within_limits(result) else None
            jac = self._jacobian_rows(q_deg, tool_rows, pose, prefixes)
            for row in jac[3:]:
                row[:] = [v * 300.0 for v in row]   # weight rotation like ~300 mm of lever arm
            scaled = err[:3] + [v * 300.0 for v in err[3:]]
            # (J J^T + damping * I): the damping (1.0) is added to every element times the
            # identity's; J J^T is symmetric to the bit (x*y == y*x, the same order of the sums)
            normal = [[0.0] * len(jac) for _ in jac]
            for i, row in enumerate(jac):
                normal[i][i] = dot(row, row) + 1.0
                for j in range(i):
                    normal[i][j] = normal[j][i] = dot(row, jac[j]) + 0.0
            x = solve(normal, scaled)
            q = [v + dot(column, x) for v, column in zip(q, zip(*jac))]   # q + J^T x
        return None

    @staticmethod
    def _times_rows(left: list, right: list) -> list:
        """left @ right for 4x4 row lists: `dm.matmul`'s sums, in its order."""
        columns = list(zip(*right))
        return [[0.0 + r0 * c0 + r1 * c1 + r2 * c2 + r3 * c3 for c0, c1, c2, c3 in columns]
                for r0, r1, r2, r3 in left]

    @staticmethod
    def _pose_error_rows(target: list, cur: list) -> list:
        """`_pose_error` on row lists (the same operations in the same order), from the current
        pose `cur` (`fk`'s rows)."""
        t0, t1, t2 = target[0], target[1], target[2]
        c0, c1, c2 = cur[0], cur[1], cur[2]
        dp = [t0[3] - c0[3], t1[3] - c1[3], t2[3] - c2[3]]
        # r_err = target[:3, :3] @ cur[:3, :3].T: element (i, j) sums target row i times cur row j
        r_err = [[0.0 + t[0] * c[0] + t[1] * c[1] + t[2] * c[2] for c in (c0, c1, c2)] for t in (t0, t1, t2)]
        angle = dm.acos(max(-1.0, min(1.0, (r_err[0][0] + r_err[1][1] + r_err[2][2] - 1) / 2)))
        if angle < 1e-12:
            return dp + [0.0, 0.0, 0.0]
        axis = [r_err[2][1] - r_err[1][2], r_err[0][2] - r_err[2][0], r_err[1][0] - r_err[0][1]]
        norm = math.sqrt(dm._dot_floats(axis, axis))
        return dp + ([v / norm * angle for v in axis] if norm > 1e-12 else [0.0, 0.0, 0.0])

    def _jacobian_rows(self, q_deg: list, tool: list | None, base: list, prefixes: list) -> list:
        """`_jacobian` on row lists (the same operations in the same order), as rows; `base` is
        the pose at `q_deg` (`fk`'s rows), `prefixes` the products of its first links."""
        b0, b1, b2 = base[0], base[1], base[2]
        h = 1e-6
        step, two_h = dm.degrees(h), 2 * h
        columns = []
        for i in range(len(q_deg)):
            dq = list(q_deg)
            dq[i] += step
            moved = self._chain(dq, i, prefixes[i]) + [[0.0, 0.0, 0.0, 1.0]]
            if tool is not None:
                moved = self._times_rows(moved, tool)
            m0, m1, m2 = moved[0], moved[1], moved[2]

            def r_d(m: list, b: list) -> float:   # (moved[:3, :3] @ base[:3, :3].T)[row m, column b]
                return 0.0 + m[0] * b[0] + m[1] * b[1] + m[2] * b[2]
            columns.append(((m0[3] - b0[3]) / h, (m1[3] - b1[3]) / h, (m2[3] - b2[3]) / h,
                            (r_d(m2, b1) - r_d(m1, b2)) / two_h, (r_d(m0, b2) - r_d(m2, b0)) / two_h,
                            (r_d(m1, b0) - r_d(m0, b1)) / two_h))
        return [list(row) for row in zip(*columns)]

    def _ik_arrays(self, target: np.ndarray, seed_deg: Sequence[float], tool: np.ndarray | None,
                   max_iterations: int) -> np.ndarray | None:
        """Damped least squares on numpy arrays (the reference `_ik` follows)."""
        q = np.asarray(seed_deg, dtype=float) * dm.RAD_PER_DEG
        damping = 1.0
        for _ in range(max_iterations):
            err = self._pose_error(target, q * dm.DEG_PER_RAD, tool)
            if dm.norm(err[:3]) < 1e-2 and dm.norm(err[3:]) < dm.radians(1e-2):
                result = q * dm.DEG_PER_RAD
                # Keep angles near the seed (joints rotate more than 360 deg on a TM).
                result = np.asarray(seed_deg) + (result - np.asarray(seed_deg) + 180.0) % 360.0 - 180.0
                return result if self.within_limits(result) else None
            jac = self._jacobian(q * dm.DEG_PER_RAD, tool)
            scaled = err.copy()
            scaled[3:] *= 300.0  # weight rotation like ~300 mm of lever arm
            jac_s = jac.copy()
            jac_s[3:] *= 300.0
            step = dm.matmul(jac_s.T, dm.solve(dm.matmul(jac_s, jac_s.T) + damping * np.eye(6), scaled))
            q = q + step
        return None

    def _pose_error(self, target: np.ndarray, q_deg: np.ndarray, tool: np.ndarray | None) -> np.ndarray:
        cur = self.fk(q_deg, tool)
        dp = target[:3, 3] - cur[:3, 3]
        r_err = dm.matmul(target[:3, :3], cur[:3, :3].T)
        angle = dm.acos(max(-1.0, min(1.0, (dm.trace3(r_err) - 1) / 2)))
        if angle < 1e-12:
            dr = np.zeros(3)
        else:
            axis = np.array([r_err[2, 1] - r_err[1, 2], r_err[0, 2] - r_err[2, 0], r_err[1, 0] - r_err[0, 1]])
            norm = dm.norm(axis)
            dr = axis / norm * angle if norm > 1e-12 else np.zeros(3)
        return np.concatenate([dp, dr])

    def _jacobian(self, q_deg: np.ndarray, tool: np.ndarray | None) -> np.ndarray:
        """Geometric Jacobian per radian (numeric differences of fk)."""
        prefixes = [self._IDENTITY_ROWS]    # prefixes[i]: the product of links 0..i-1
        base = np.array(self._chain(q_deg, prefixes=prefixes) + [[0.0, 0.0, 0.0, 1.0]])
        if tool is not None:
            base = dm.matmul(base, tool)
        jac = np.zeros((6, 6))
        h = 1e-6
        for i in range(6):
            dq = np.array(q_deg, dtype=float)
            dq[i] += dm.degrees(h)
            # fk(dq): links before i are the base's (same angles), so resume from their product
            moved = np.array(self._chain(dq, i, prefixes[i]) + [[0.0, 0.0, 0.0, 1.0]])
            if tool is not None:
                moved = dm.matmul(moved, tool)
            jac[:3, i] = (moved[:3, 3] - base[:3, 3]) / h
            r_d = dm.matmul(moved[:3, :3], base[:3, :3].T)
            jac[3:, i] = np.array([r_d[2, 1] - r_d[1, 2], r_d[0, 2] - r_d[2, 0], r_d[1, 0] - r_d[0, 1]]) / (2 * h)
        return jac


# --------------------------------------------------------------------------- timing


def trapezoid_duration_s(distance: float, top_speed: float, accel_s: float) -> float:
    """Duration of a rest-to-rest trapezoid (see module docstring)."""
    if distance <= 0.0:
        return 0.0
    if top_speed <= 0.0:
        raise ValueError("top speed must be positive")
    if accel_s <= 0.0:
        return distance / top_speed
    if distance >= top_speed * accel_s:
        return distance / top_speed + accel_s
    return 2.0 * math.sqrt(distance * accel_s / top_speed)


def _round_sqrt(square: Fraction) -> int:
    """The integer nearest to sqrt(square) (square >= 0), ties to even: exact."""
    num, den = square.numerator, square.denominator
    root = math.isqrt(num // den)          # floor(sqrt(x)) == isqrt(floor(x))
    # compare sqrt(x) with root + 1/2:  4*x  vs  (2*root + 1)**2
    lhs, rhs = 4 * num, (2 * root + 1) ** 2 * den
    if lhs > rhs or (lhs == rhs and root & 1):
        return root + 1
    return root


def _trapezoid_square(distance: Fraction, top_speed: Fraction, accel_s: Fraction) -> Fraction:
    """The square of the exact trapezoid duration in seconds (see the module docstring)."""
    if distance <= 0:
        return Fraction(0)
    if top_speed <= 0:
        raise ValueError("top speed must be positive")
    if accel_s <= 0:
        return (distance / top_speed) ** 2
    if distance >= top_speed * accel_s:
        return (distance / top_speed + accel_s) ** 2
    return 4 * distance * accel_s / top_speed       # (2 * sqrt(D * ta / v)) ** 2


@dataclass(frozen=True)
class SegmentTiming:
    """The inputs of a segment's timing, each an exact number (a float is the exact binary
    value it holds). ``distances[i]`` runs at ``top_speeds[i]``; the slowest axis sets the
    duration. ``blend`` is a percentage of the deceleration, or a radius in mm when
    ``blend_is_radius`` (overlapping the time the last ``blend`` mm take at ``blend_speed``)."""

    distances: tuple[Fraction, ...]
    top_speeds: tuple[Fraction, ...]
    accel_s: Fraction
    time_scale: Fraction
    blend: Fraction = Fraction(0)
    blend_is_radius: bool = False
    blend_speed: Fraction = Fraction(1)
    settle_ms: Fraction = Fraction(0)

    def times_ns(self) -> tuple[int, int, int, int]:
        """(duration, acceleration, blend, settle) in whole nanoseconds of motion time."""
        ns_per_s = self.time_scale * NS_PER_S
        scale_sq = ns_per_s * ns_per_s
        duration_sq = max((_trapezoid_square(d, v, self.accel_s) for d, v in zip(self.distances, self.top_speeds)),
                          default=Fraction(0))
        decel_sq = min(self.accel_s * self.accel_s, duration_sq / 4)     # min(ta, duration / 2) ** 2
        blend_sq = Fraction(0)
        if self.blend > 0:
            if self.blend_is_radius:
                # Choice: a radius r overlaps the time the motion needs for its last r mm:
                # fraction = min(1, r / max(v * decel / 2, 1e-9))
                denominator_sq = max(self.blend_speed * self.blend_speed / 4 * decel_sq, Fraction(1e-9) ** 2)
                fraction_sq = min(Fraction(1), self.blend * self.blend / denominator_sq)
            else:
                fraction_sq = min(Fraction(1), self.blend / 100) ** 2
            blend_sq = fraction_sq * decel_sq
        return (_round_sqrt(duration_sq * scale_sq), _round_sqrt(decel_sq * scale_sq),
                _round_sqrt(blend_sq * scale_sq), round(self.settle_ms / 1000 * ns_per_s))


def trapezoid_fraction(t_s: float, duration_s: float, accel_s: float) -> float:
    """Fraction of the distance covered at ``t_s`` of a trapezoid of ``duration_s``."""
    if duration_s <= 0.0 or t_s >= duration_s:
        return 1.0
    if t_s <= 0.0:
        return 0.0
    ta = min(accel_s, duration_s / 2.0)
    if ta <= 0.0:
        return t_s / duration_s
    cruise = duration_s - 2.0 * ta
    total = ta + cruise  # distance in units of top speed (area under the profile)
    if t_s < ta:
        covered = 0.5 * t_s * t_s / ta
    elif t_s < ta + cruise:
        covered = 0.5 * ta + (t_s - ta)
    else:
        rem = duration_s - t_s
        covered = total - 0.5 * rem * rem / ta
    return covered / total


# --------------------------------------------------------------------------- segments


@dataclass
class Segment:
    """One planned motion.  ``space`` is ``joint`` (interpolate joints) or ``cart`` (interpolate the
    TCP pose in the robot base; ``circle`` adds the arc)."""

    space: str
    start_joints: np.ndarray
    end_joints: np.ndarray
    start_tcp: np.ndarray  # 4x4 in robot base
    end_tcp: np.ndarray
    duration_ns: int
    accel_ns: int
    blend_ns: int = 0  # overlap with the next motion (0 = stop at target)
    settle_ns: int = 0
    circle: dict[str, Any] | None = None
    label: str = ""
    start_ns: int = 0  # motion time when it started (set by the executor)
    timing: SegmentTiming | None = None  # what the four times above were computed from

    @property
    def total_ns(self) -> int:
        return self.duration_ns + self.settle_ns

    @property
    def handover_ns(self) -> int:
        """Motion-time offset at which a queued next motion may start."""
        return self.total_ns - self.blend_ns if self.blend_ns > 0 else self.total_ns

    def fraction(self, now_ns: int) -> float:
        return trapezoid_fraction((now_ns - self.start_ns) / NS_PER_S, self.duration_ns / NS_PER_S,
                                  self.accel_ns / NS_PER_S)

    def tcp_at(self, now_ns: int) -> np.ndarray:
        s = self.fraction(now_ns)
        out = np.eye(4)
        if self.circle is not None:
            c = self.circle
            angle = c["sweep"] * s
            out[:3, 3] = c["center"] + c["radius"] * (dm.cos(angle) * c["u"] + dm.sin(angle) * c["v"])
        else:
            out[:3, 3] = self.start_tcp[:3, 3] + s * (self.end_tcp[:3, 3] - self.start_tcp[:3, 3])
        out[:3, :3] = slerp_matrix(self.start_tcp[:3, :3], self.end_tcp[:3, :3], s)
        return out

    def joints_at(self, now_ns: int) -> np.ndarray | None:
        """Joint angles at ``now_ns`` for joint-space motions (None for Cartesian ones)."""
        if self.space != "joint":
            return None
        s = self.fraction(now_ns)
        return self.start_joints + s * (self.end_joints - self.start_joints)


@dataclass
class Marker:
    """A non-motion queue item, applied when reached: a QueueTag, base/TCP/load change, DO write."""

    kind: str  # "tag" / "base" / "tcp" / "load" / "do"
    value: Any
    owner: int | None = None  # connection that queued it (tag notifications, spec §5.3)


QueueItem = Segment | Marker


@dataclass
class ExecutorEvent:
    """A marker reached at motion time ``at_ns``."""

    at_ns: int
    marker: Marker


class MotionExecutor:
    """The FIFO motion queue (spec §8 "two queues", (b)): motions and markers in strict order."""

    def __init__(self, kinematics: Kinematics, joints_deg: Sequence[float], tool: np.ndarray | None = None):
        self.kin = kinematics
        self.queue: deque[QueueItem] = deque()
        self.active: list[Segment] = []  # the current motion last; earlier ones still blending out
        self.rest_joints = np.array(joints_deg, dtype=float)
        self.rest_tcp = kinematics.fk(self.rest_joints, tool)
        self.time_ns = 0
        self.stalled = False  # fault "busy": motion never progresses
        # set by an `InProcessLink` that lets the clocks lag on quiet steps (see there): brings
        # `time_ns` up to date before the pose is read
        self.catch_up: Callable[[], None] | None = None

    # -- queries ---------------------------------------------------------------------------------

    @property
    def idle(self) -> bool:
        return not self.queue and not self.active

    @property
    def moving(self) -> bool:
        return bool(self.active)

    def next_event_ns(self) -> int | None:
        """Motion time of the next state change (a queue item starting or the motion ending)."""
        if self.stalled:
            return None
        # the earlier of the queue head's start and the running motion's end (no list: this runs
        # several times a VM scan in lockstep)
        head = self._head_start_ns()
        if not self.active:
            return head
        last = self.active[-1]
        end = last.start_ns + last.total_ns
        return end if head is None or end < head else head

    def current_tcp(self) -> np.ndarray:
        if self.catch_up is not None:
            self.catch_up()
        if not self.active:
            return self.rest_tcp
        current = self.active[-1]
        tcp = current.tcp_at(self.time_ns).copy()
        for older in self.active[:-1]:  # superposition of what is left of blended motions
            tcp[:3, 3] += older.tcp_at(self.time_ns)[:3, 3] - older.end_tcp[:3, 3]
        return tcp

    def current_joints(self, tool: np.ndarray | None = None) -> np.ndarray:
        if self.catch_up is not None:
            self.catch_up()
        if not self.active:
            return self.rest_joints
        current = self.active[-1]
        joints = current.joints_at(self.time_ns)
        if joints is not None:
            for older in self.active[:-1]:
                older_j = older.joints_at(self.time_ns)
                if older_j is not None:
                    joints = joints + older_j - older.end_joints
            return joints
        solved = self.kin.ik(self.current_tcp(), current.start_joints, tool)
        return solved if solved is not None else current.start_joints

    # -- changes ---------------------------------------------------------------------------------

    def enqueue(self, item: QueueItem) -> None:
        self.queue.append(item)

    def advance(self, now_ns: int) -> list[ExecutorEvent]:
        """Run the queue up to motion time ``now_ns``; return the markers reached, in order, each
        with the exact motion time at which it was reached.  Events are processed in time order, so
        the outcome does not depend on how finely time is stepped."""
        events: list[ExecutorEvent] = []
        if self.stalled:
            return events
        if not self.queue and not self.active:  # idle: only the clock moves
            if now_ns > self.time_ns:
                self.time_ns = now_ns
            return events
        while True:
            start_at = self._head_start_ns()
            end_at = self.active[-1].start_ns + self.active[-1].total_ns if self.active else None
            if start_at is not None and start_at <= now_ns and (end_at is None or start_at <= end_at):
                item = self.queue.popleft()
                self.time_ns = max(self.time_ns, start_at)
                if isinstance(item, Marker):
                    events.append(ExecutorEvent(self.time_ns, item))
                    continue
                item.start_ns = self.time_ns
                self.active = [seg for seg in self.active
                               if seg.blend_ns > 0 and seg.start_ns + seg.total_ns > item.start_ns]
                self.active.append(item)
            elif end_at is not None and end_at <= now_ns:
                current = self.active[-1]
                self.time_ns = max(self.time_ns, end_at)
                self.rest_joints, self.rest_tcp = current.end_joints, current.end_tcp
                self.active = []
            else:
                break
        self.time_ns = max(self.time_ns, now_ns)
        return events

    def _head_start_ns(self) -> int | None:
        """Motion time at which the queue head can start (None: queue empty)."""
        if not self.queue:
            return None
        if not self.active:
            return self.time_ns
        current = self.active[-1]
        if current.blend_ns > 0 and self._motion_follows():
            # Blending: the next motion (and any marker before it) starts at the hand-over.
            return max(self.time_ns, current.start_ns + current.handover_ns)
        return max(self.time_ns, current.start_ns + current.total_ns)

    def _motion_follows(self) -> bool:
        return any(isinstance(item, Segment) for item in self.queue)

    def stop_and_clear(self, tool: np.ndarray | None = None) -> list[Marker]:
        """Stop at the current pose now (Choice §8: deceleration time not modelled) and drop every
        queued item; return the dropped markers."""
        if self.active:
            self.rest_tcp = self.current_tcp()
            self.rest_joints = self.current_joints(tool)
        self.active = []
        dropped = [item for item in self.queue if isinstance(item, Marker)]
        self.queue.clear()
        return dropped


# --------------------------------------------------------------------------- planning


class PlanError(Exception):
    """A motion the robot rejects: unreachable target, joint limit, bad argument value."""


@dataclass
class PlannedState:
    """Where the robot will be once everything queued so far has run: planning starts here."""

    joints: np.ndarray
    tcp: np.ndarray  # 4x4 TCP in robot base
    base: np.ndarray = field(default_factory=lambda: np.eye(4))
    tool: np.ndarray = field(default_factory=lambda: np.eye(4))

    def copy(self) -> "PlannedState":
        return PlannedState(self.joints.copy(), self.tcp.copy(), self.base.copy(), self.tool.copy())


class Planner:
    """Turns validated motion calls into :class:`Segment` objects (see module docstring)."""

    def __init__(self, kinematics: Kinematics, settings: EmulatorSettings = DEFAULT_SETTINGS):
        self.kin = kinematics
        self.settings = settings
        # joint_motion's timing by its exact inputs (`_JOINT_TIMINGS`): a script is planned
        # twice (the dry run, then the run) and a cycle repeats its motions; `SegmentTiming` is
        # immutable
        self._joint_timings = _JOINT_TIMINGS

    def _accel_s(self, accel_ms: float) -> Fraction:
        return max(Fraction(accel_ms), Fraction(self.settings.min_accel_ms)) / 1000

    def _timing(self, distances: Sequence[Fraction], speeds: Sequence[Fraction], accel_ms: float, blend: float,
                blend_is_radius: bool, blend_speed: Fraction, precise: bool) -> SegmentTiming:
        return SegmentTiming(tuple(distances), tuple(speeds), self._accel_s(accel_ms),
                             Fraction(self.settings.time_scale), Fraction(max(blend, 0)), blend_is_radius,
                             blend_speed, Fraction(self.settings.precise_settle_ms) if precise else Fraction(0))

    def joint_motion(self, state: PlannedState, target_joints: np.ndarray, speed_pct: float, accel_ms: float,
                     blend_pct: float, precise: bool, label: str) -> Segment:
        if not self.kin.within_limits(target_joints):
            raise PlanError("joint target outside the joint limits")
        target_array, joints_array = np.asarray(target_joints), np.asarray(state.joints)
        key = (target_array.dtype.str, target_array.shape, target_array.tobytes(), joints_array.dtype.str,
               joints_array.shape, joints_array.tobytes(), speed_pct, accel_ms, blend_pct, precise, id(self.settings))
        cacheable = target_array.dtype.kind == joints_array.dtype.kind == "f"
        known = self._joint_timings.get(key) if cacheable else None
        if known is not None and known[0] is self.settings:
            timing, times = known[1], known[2]
        else:
            pct = Fraction(speed_pct) / 100
            speeds = [Fraction(v) * pct for v in self.settings.max_joint_speed_deg_s]
            distances = [abs(Fraction(float(t)) - Fraction(float(q))) for t, q in zip(target_joints, state.joints)]
            timing = self._timing(distances, speeds, accel_ms, blend_pct, False, Fraction(1), precise)
            times = timing.times_ns()
            if cacheable:
                if len(self._joint_timings) >= _KEPT_RESULTS:
                    self._joint_timings.clear()
                self._joint_timings[key] = (self.settings, timing, times)
        duration_ns, accel_ns, blend_ns, settle_ns = times
        end_tcp = self.kin.fk(target_joints, state.tool)
        seg = Segment("joint", state.joints.copy(), target_joints.copy(), state.tcp.copy(), end_tcp,
                      duration_ns, accel_ns, blend_ns, settle_ns, label=label, timing=timing)
        state.joints, state.tcp = target_joints.copy(), end_tcp
        return seg

    def solve(self, state: PlannedState, tcp_target: np.ndarray) -> np.ndarray:
        joints = self.kin.ik(tcp_target, state.joints, state.tool)
        if joints is None:
            raise PlanError("target not reachable")
        return joints

    def cart_motion(self, state: PlannedState, tcp_target: np.ndarray, speed: float, speed_is_pct: bool,
                    accel_ms: float, blend: float, blend_is_radius: bool, precise: bool, label: str,
                    circle: dict[str, Any] | None = None, path_length: float | None = None) -> Segment:
        joints = self.solve(state, tcp_target)
        max_speed = Fraction(self.settings.max_tcp_speed_mm_s)
        fraction = Fraction(speed) / 100 if speed_is_pct else Fraction(speed) / max_speed
        v = fraction * max_speed
        w = fraction * Fraction(self.settings.max_tcp_rot_speed_deg_s)
        length = path_length if path_length is not None else dm.norm(tcp_target[:3, 3] - state.tcp[:3, 3])
        rot = rotation_angle_deg(state.tcp[:3, :3], tcp_target[:3, :3])
        timing = self._timing([Fraction(length), Fraction(rot)], [v, w], accel_ms, blend, blend_is_radius, v, precise)
        duration_ns, accel_ns, blend_ns, settle_ns = timing.times_ns()
        seg = Segment("cart", state.joints.copy(), joints, state.tcp.copy(), tcp_target.copy(),
                      duration_ns, accel_ns, blend_ns, settle_ns, circle=circle, label=label, timing=timing)
        state.joints, state.tcp = joints, tcp_target.copy()
        return seg

    def circle_motion(self, state: PlannedState, via: np.ndarray, end: np.ndarray, arc_angle_deg: float,
                      speed: float, speed_is_pct: bool, accel_ms: float, blend: float, precise: bool,
                      label: str) -> Segment:
        """Circle through start, ``via`` and ``end`` (4x4, robot base).  ``arc_angle_deg`` != 0:
        sweep that angle keeping the start orientation; 0: stop at ``end`` (spec §7)."""
        p0, p1, p2 = state.tcp[:3, 3], via[:3, 3], end[:3, 3]
        a, b = p1 - p0, p2 - p0
        normal = dm.cross(a, b)
        if dm.norm(normal) < 1e-6:
            raise PlanError("circle points are collinear")
        normal /= dm.norm(normal)
        # Circumcentre of the three points.
        a_x_b = dm.cross(a, b)
        center = p0 + (dm.dot(b, b) * dm.cross(a_x_b, a) + dm.dot(a, a) * dm.cross(b, a_x_b)) \
            / (2.0 * dm.dot(a_x_b, a_x_b))
        radius = dm.norm(p0 - center)
        u = (p0 - center) / radius
        v = dm.cross(normal, u)

        def angle_of(p: np.ndarray) -> float:
            return dm.atan2(dm.dot(p - center, v), dm.dot(p - center, u)) % (2 * dm.PI)

        if arc_angle_deg:
            sweep = dm.radians(arc_angle_deg)
            target = np.eye(4)
            target[:3, :3] = state.tcp[:3, :3]
            target[:3, 3] = center + radius * (dm.cos(sweep) * u + dm.sin(sweep) * v)
        else:
            sweep = angle_of(p2)  # via lies between start and end by construction of v
            target = end
        circle = {"center": center, "radius": radius, "u": u, "v": v, "sweep": sweep}
        return self.cart_motion(state, target, speed, speed_is_pct, accel_ms, blend, False, precise, label,
                                circle=circle, path_length=abs(sweep) * radius)
