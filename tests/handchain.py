"""A machine's kinematics written out by hand from its description file: the reference the package's chain
(:mod:`mtmcal_bayes.machines.chain`) and the programs of ``ncgen`` are checked against (tests/test_chain_reference.py,
tests/test_workflow_described.py).

Read from the TOML file with :mod:`tomllib`, not through the package's reader.  The configuration
``w-<work axes>b<tool axes>(C1)-t``: the letters between ``w-`` and ``b`` carry the workpiece, the first the one
nearest the workpiece; those between ``b`` and ``(`` carry the tool, the first the one on the bed.  A rotary
axis of direction ``±e`` turns by its command θ right-handed about its direction through its ``point_mm``
(the frame axis' rotation matrix at ±θ, written out below); one given as a vector k (an inclined axis, SPEC §21) by
Rodrigues' formula about k, its location errors along and about its basis u (the frame axis least along k, made
perpendicular to it), v = k × u and about k itself; a linear axis moves the tool side by ``+q`` along
its frame axis (tilted by its squareness errors, ISO 230-1's form: the direction of motion alone) and the
workpiece side by ``−q``.  A location error of a body (an axis' carried body, or the
spindle's, ``"C1"``) is ``v ↦ R(ε)(v − p) + p + δ`` with ``R(ε)`` by Rodrigues' formula and ``p`` the body's
``point_mm``, applied outside that body's own motion.  Units: mm and rad.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np

import mtmcal_bayes

MACHINES = Path(mtmcal_bayes.__file__).parent / "datasets" / "machines"
FRAME = "XYZ"


def rot_x(t: float) -> np.ndarray:
    c, s = np.cos(t), np.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(t: float) -> np.ndarray:
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(t: float) -> np.ndarray:
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


ROTATION = {"X": rot_x, "Y": rot_y, "Z": rot_z}


def rodrigues(eps: np.ndarray) -> np.ndarray:
    """The rotation by the rotation vector ``eps`` (3,) rad."""
    angle = float(np.linalg.norm(eps))
    if angle == 0.0:
        return np.eye(3)
    kx, ky, kz = eps / angle
    K = np.array([[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K


def unit(direction) -> np.ndarray:
    """``"-Z"`` -> (0, 0, -1); a vector (an inclined direction) -> it normalised."""
    if not isinstance(direction, str):
        v = np.asarray(direction, float)
        return v / np.linalg.norm(v)
    e = np.zeros(3)
    e[FRAME.index(direction[1])] = 1.0 if direction[0] == "+" else -1.0
    return e


class HandMachine:
    """The built-in machine type ``name``, nominal; ``errors`` {body: (ε (3,) rad, δ (3,) mm)} its location
    errors (none by default)."""

    def __init__(self, name: str):
        t = tomllib.loads((MACHINES / f"{name}.toml").read_text(encoding="utf-8"))
        work, tool = t["configuration"][2:].split("(")[0].split("b")
        self.work = [c for c in work if c != "'"]  # nearest the workpiece first
        self.tool = list(tool)  # the bed's first
        self.axes = t["axes"]
        self.spindle_direction = unit(t["spindle"]["direction"])
        self.spindle_point = np.array(t["spindle"]["point_mm"], float)
        self.squareness = t.get("squareness", "motion")
        self.errors: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.tilts: dict[str, np.ndarray] = {}  # linear axis -> rotation vector of its direction of motion

    def rotary(self, letter: str) -> bool:
        return "direction" in self.axes.get(letter, {})  # a linear axis may have no table (no travel given)

    def direction(self, letter: str) -> np.ndarray:
        return unit(self.axes[letter]["direction"])

    def point(self, body: str) -> np.ndarray:
        if body == "C1":
            return self.spindle_point
        return np.array(self.axes.get(body, {}).get("point_mm", [0.0, 0.0, 0.0]), float)

    def tool_home(self, length: float) -> np.ndarray:
        """The tool point at the home pose for a programmed length ``length``."""
        return self.spindle_point + length * self.spindle_direction

    def motion(self, letter: str, q: float, v: np.ndarray, *, work: bool, turn_only: bool = False) -> np.ndarray:
        """Axis ``letter`` at command ``q`` applied to ``v`` (3,) (``turn_only``: a direction, no translation)."""
        if self.rotary(letter):
            d = self.axes[letter]["direction"]
            R = ROTATION[d[1]](q if d[0] == "+" else -q) if isinstance(d, str) else rodrigues(q * unit(d))
            if turn_only:
                return R @ v
            p = self.point(letter)
            return R @ (v - p) + p
        if turn_only:
            return v
        e = rodrigues(self.tilts.get(letter, np.zeros(3))) @ unit("+" + letter)
        return v + (-q if work else q) * e

    def inclined(self, letter: str) -> bool:
        """Whether rotary axis ``letter`` is given by a vector off the frame axes."""
        return self.rotary(letter) and not isinstance(self.axes[letter]["direction"], str)

    def basis(self, letter: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(u, v, k)`` of inclined axis ``letter``: u the frame axis with the smallest |eᵢ·k| (the first on a tie)
        with its part along k taken off, normalised; v = k × u."""
        k = self.direction(letter)
        e = np.eye(3)[int(np.argmin(np.abs(k)))]
        u = e - (e @ k) * k
        u /= np.linalg.norm(u)
        return u, np.cross(k, u), k

    def error_axis(self, symbol: str) -> np.ndarray:
        """The unit vector a location error moves along or turns about: its frame axis, or on an inclined axis its
        basis vector (``E_U0B``, ``E_RU0B``: u; ``E_V0B``, ``E_RV0B``: v; ``E_B0B``, its zero: k)."""
        body, role, comp = body_of(symbol, self)
        if comp is not None:
            return np.eye(3)[comp]
        u, v, k = self.basis(body)
        name = symbol[2:symbol.index("0")]
        return {"U": u, "V": v, "RU": u, "RV": v}.get(name, k)

    def displace(self, body: str, v: np.ndarray) -> np.ndarray:
        if body not in self.errors:
            return v
        eps, delta = self.errors[body]
        p = self.point(body)
        return rodrigues(eps) @ (v - p) + p + delta

    def tool_point(self, t: np.ndarray, q: dict) -> np.ndarray:
        """Where the tool-side point ``t`` (its place at the home pose) is at commands ``q``."""
        v = self.displace("C1", np.asarray(t, float))
        for letter in reversed(self.tool):
            v = self.displace(letter, self.motion(letter, q[letter], v, work=False))
        return v

    def work_point(self, w: np.ndarray, q: dict) -> np.ndarray:
        """Where the workpiece-side point ``w`` (its place at the home pose) is at commands ``q``."""
        v = np.asarray(w, float)
        for letter in self.work:
            v = self.displace(letter, self.motion(letter, q[letter], v, work=True))
        return v

    def axis_line(self, letter: str, q: dict) -> tuple[np.ndarray, np.ndarray]:
        """Nominal (point, direction) of rotary axis ``letter``'s line at commands ``q``: taken down the axes
        below it on its side."""
        work = letter in self.work
        side = self.work if work else list(reversed(self.tool))
        below = side[side.index(letter) + 1:]
        p, k = self.point(letter), self.direction(letter)
        for b in below:
            p = self.motion(b, q[b], p, work=work)
            k = self.motion(b, q[b], k, work=work, turn_only=True)
        return p, k


#: squareness symbol -> (the linear axis whose direction of motion it tilts, the frame axis it turns about)
SQUARENESS = {"E_C0X": ("X", 2), "E_B0X": ("X", 1), "E_A0Y": ("Y", 0)}


def body_of(symbol: str, hand: HandMachine | None = None) -> tuple[str, str, int | None]:
    """``(body, "position" or "orientation", frame component)`` of an ISO 230-7 location error symbol:
    ``E_X0C`` (C's line along X), ``E_A0C`` (C's orientation about X), ``E_X(0C1)B`` (the spindle's, along X).  On
    an inclined axis of ``hand`` (SPEC §21: ``E_U0B``, ``E_V0B`` positions, ``E_RU0B``, ``E_RV0B``, ``E_B0B``
    orientations) the component is None: :meth:`HandMachine.error_axis` gives its vector."""
    letter = symbol[2]
    body = "C1" if "(0C1)" in symbol else symbol.split("0")[-1]
    if hand is not None and body != "C1" and hand.inclined(body):
        return body, "position" if symbol[2:symbol.index("0")] in ("U", "V") else "orientation", None
    if letter in FRAME:
        return body, "position", FRAME.index(letter)
    return body, "orientation", "ABC".index(letter)
