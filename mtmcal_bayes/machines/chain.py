"""The kinematic chain of any described machine (SPEC §19), vectorised over draws and points.

A point carried by the tool side (a ball or stylus centre, given at the home pose in the machine frame) is
taken down the chain from the spindle to the bed; a point of the workpiece side likewise from the workpiece
to the bed::

    T(q) = D_1 M_1(q_1) D_2 M_2(q_2) … D_s t,      W(q) = D'_1 M'_1(q'_1) … w

``M_i`` is axis i's nominal motion (a rotary axis: an exact rotation about its nominal line through
``point_mm``; a linear axis: a translation along its direction of motion, the opposite way on the workpiece
side) and ``D_i`` the location errors of the body it carries (:mod:`mtmcal_bayes.machines.deviations`): the
rigid displacement ``v ↦ R(ε)(v − p) + p + δ`` with ε the orientation errors (one rotation vector, exact:
``expm([ε]×)``: the sum of each error times the unit vector it turns about), p the axis' ``point_mm`` and δ its
position errors (the sum of each times the unit vector it lies along: a frame axis, or an inclined axis' own basis
vector, SPEC §21); it sits outside the axis' own motion, so
a position error moves the axis line and everything the axes below it do carries it along.

The squareness of the linear axes acts in one of two forms: ``"motion"`` (ISO 230-1): it tilts the axis'
direction of motion only; ``"rigid"`` (the thesis' ``M_XY``, ``M_YZ`` of Eq 2.10): a rotation about the frame
origin of the body a linear axis carries, its own travel included: with the linear axes L1, L2, L3 from the
bed, the two errors that involve L1 turn L2's body and the one between L2 and L3 turns L3's.  On the thesis
machine the rigid form makes this chain Eq 2.10 as printed (``htm-literal``), which the tests hold to 1e-9 mm.

Shapes: ``n`` draws, ``k`` points.  Commands are ``{letter: (k,)}`` (mm, rad; a linear axis' may be ``(n, k)``,
one per draw, as a probe reading's are); deviation values
``{name: (n,)}`` in internal units (mm, rad); points ``(n, k, 3)`` mm.
"""

from __future__ import annotations

import numpy as np

from .description import LINEAR, SPINDLE, MachineDescription
from .deviations import SQUARENESS_ERRORS, Deviation
from .patterns import turn
from .rotations import _apply, rotation


def _step(command: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """A linear axis' travel: ``command`` (k,) or (n, k) mm along ``direction`` (3,) or (n, 3) -> (…, k, 3)."""
    return np.asarray(command)[..., None] * (direction if direction.ndim == 1 else direction[:, None, :])


def _stack(cols: list[tuple[np.ndarray, str]], dev: dict[str, np.ndarray], n: int) -> np.ndarray | None:
    """``Σ dev[name] · direction`` (n, 3) over columns ``(direction (3,), name)`` (absent names: zero); None if
    nothing is displaced.  A frame axis' column adds its value to that component alone (the arithmetic of a
    frame-named error is the component's own)."""
    if not cols or not any(name in dev for _, name in cols):
        return None
    out = np.zeros((n, 3), dtype=np.result_type(*(dev[name] for _, name in cols if name in dev)))
    for direction, name in cols:
        if name not in dev:
            continue
        nonzero = np.flatnonzero(direction)
        if len(nonzero) == 1 and direction[nonzero[0]] == 1.0:
            out[:, nonzero[0]] += dev[name]
        else:
            out += dev[name][:, None] * direction
    return out if out.any() else None


class Body:
    """The location errors of one body: rotation vector and displacement columns ``(direction (3,), name)``."""

    def __init__(self, point: np.ndarray):
        self.point = point
        self.rot: list[tuple[np.ndarray, str]] = []
        self.pos: list[tuple[np.ndarray, str]] = []

    def vectors(self, dev: dict[str, np.ndarray], n: int) -> tuple[np.ndarray | None, np.ndarray | None]:
        """``(ε (n, 3) or None, δ (n, 3) or None)`` from the deviation values (absent names: zero)."""
        return _stack(self.rot, dev, n), _stack(self.pos, dev, n)

    def displace(self, v: np.ndarray, dev: dict[str, np.ndarray]) -> np.ndarray:
        """``R(ε)(v − p) + p + δ`` for ``v`` (n, k, 3)."""
        eps, delta = self.vectors(dev, len(v))
        if eps is not None:
            v = _apply(rotation(eps), v - self.point) + self.point
        if delta is not None:
            v = v + delta[:, None, :]
        return v

    def undo(self, v: np.ndarray, dev: dict[str, np.ndarray]) -> np.ndarray:
        """The inverse of :meth:`displace`."""
        eps, delta = self.vectors(dev, len(v))
        if delta is not None:
            v = v - delta[:, None, :]
        if eps is not None:
            v = _apply(np.transpose(rotation(eps), (0, 2, 1)), v - self.point) + self.point
        return v


class Chain:
    """The chain of ``desc`` with its ``deviations`` (:class:`~mtmcal_bayes.machines.deviations.Deviation`)."""

    def __init__(self, desc: MachineDescription, deviations: list[Deviation], squareness: str | None = None):
        self.desc = desc
        self.squareness = squareness or desc.squareness
        self.bodies: dict[str, Body] = {a.letter: Body(a.point) for a in desc.axes.values()}
        self.bodies[SPINDLE] = Body(desc.spindle.point)
        self.tilts: dict[str, list[tuple[int, str]]] = {a: [] for a in LINEAR}  # motion-form squareness
        rigid_body = self._rigid_bodies() if self.squareness == "rigid" else {}
        for d in deviations:
            if d.role == "squareness":
                if self.squareness == "rigid":
                    self.bodies[rigid_body[d.symbol]].rot.append((d.vector, d.name))
                else:
                    self.tilts[d.body].append((d.component, d.name))
            elif d.role == "orientation":
                self.bodies[d.body].rot.append((d.vector, d.name))
            else:
                self.bodies[d.body].pos.append((d.vector, d.name))

    def _rigid_bodies(self) -> dict[str, str]:
        """Squareness symbol -> the linear axis whose body it turns in the rigid form."""
        stack = [a.letter for a in self.desc.tool_chain if not a.rotary]
        if len(stack) != 3:
            raise ValueError("the rigid squareness form needs the three linear axes on the tool side")
        out = {}
        for sym, (_, tilted, ref) in SQUARENESS_ERRORS.items():
            upper = max(stack.index(tilted), stack.index(ref))
            out[sym] = stack[1] if stack[0] in (tilted, ref) else stack[upper]
        return out

    def _direction(self, letter: str, dev: dict[str, np.ndarray], n: int) -> np.ndarray:
        """Direction of motion of linear axis ``letter``: ``(3,)`` nominal or ``(n, 3)`` tilted."""
        e = np.zeros(3)
        e[LINEAR.index(letter)] = 1.0
        tilt = [(c, name) for c, name in self.tilts[letter] if name in dev]
        if not tilt:
            return e
        eps = np.zeros((n, 3), dtype=np.result_type(*(dev[name] for _, name in tilt)))
        for comp, name in tilt:
            eps[:, comp] += dev[name]
        return rotation(eps) @ e

    def _down(self, v: np.ndarray, chain, q: dict[str, np.ndarray], dev: dict[str, np.ndarray], *, sign: float):
        """Take ``v`` down ``chain`` (axes from the bed outwards) from its top to the bed."""
        n = len(v)
        for ax in reversed(chain):
            if ax.rotary:
                v = turn(v, ax, q[ax.letter])
            else:
                d = self._direction(ax.letter, dev, n)
                v = v + _step(sign * q[ax.letter], d)
            v = self.bodies[ax.letter].displace(v, dev)
        return v

    def tool_point(self, t: np.ndarray, q: dict[str, np.ndarray], dev: dict[str, np.ndarray]) -> np.ndarray:
        """Actual position ``(n, k, 3)`` of the tool-side point ``t`` (n, k, 3) (given at the home pose) at commands
        ``q``: the spindle's location errors, then the tool side from the spindle down to the bed."""
        t = self.bodies[SPINDLE].displace(t, dev)
        return self._down(t, [a for a in self.desc.tool_chain], q, dev, sign=+1.0)

    def work_point(self, w: np.ndarray, q: dict[str, np.ndarray], dev: dict[str, np.ndarray]) -> np.ndarray:
        """Actual position ``(n, k, 3)`` of the workpiece-side point ``w`` (n, k, 3) (its place at the home pose)."""
        return self._down(w, list(self.desc.work_chain), q, dev, sign=-1.0)

    def work_frame(self, x: np.ndarray, q: dict[str, np.ndarray], dev: dict[str, np.ndarray]) -> np.ndarray:
        """The inverse of :meth:`work_point`: where a machine-frame point ``x`` (n, k, 3) at commands ``q`` sits on
        the workpiece side, as its place at the home pose (how a ball is placed where a dummy sphere is)."""
        n = len(x)
        for ax in self.desc.work_chain:
            x = self.bodies[ax.letter].undo(x, dev)
            if ax.rotary:
                x = turn(x, ax, -q[ax.letter])
            else:
                d = self._direction(ax.letter, dev, n)
                x = x + _step(q[ax.letter], d)
        return x

    def ballbar_lengths(self, length: np.ndarray, t_off: np.ndarray, q: dict[str, np.ndarray], *,
                        placement: np.ndarray, w_off: np.ndarray, dev: dict[str, np.ndarray]) -> np.ndarray:
        """The actual length ``|T − W|`` ``(n, k)`` mm of a ball bar at every point, any machine, any campaign format.

        The tool ball sits at the spindle's ``point_mm`` plus ``length`` (n, k) mm (the true tool length) along the
        spindle, offset by ``t_off`` (n, k, 3) (zero at dummy-sphere points).  The W ball of point j is placed where
        the tool ball is at point ``placement[j]`` (the index of its mount's dummy-sphere point), carried into the
        workpiece frame, offset there by ``w_off`` (n, k, 3), and carried back at point j's commands ``q``."""
        s = self.desc.spindle
        t = s.point + length[..., None] * s.direction
        T = self.tool_point(t + t_off, q, dev)
        q0 = {a: v[placement] for a, v in q.items()}
        W = self.work_point(self.work_frame(T[:, placement, :], q0, dev) + w_off, q, dev)
        diff = T - W
        return np.sqrt(np.einsum("nki,nki->nk", diff, diff))
