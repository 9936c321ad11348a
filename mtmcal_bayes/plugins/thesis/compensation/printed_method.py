"""Thesis Eqs 3.4–3.13 as printed, kept for reproduction (SPEC §7, §9 item 6).

Per block, with x = (X, Y, Z, 1) the NC command::

    P  = E_C⁻¹ E_B x                            (3.4)  ideal TCP, workpiece frame
    P′ = E_C⁻¹ M_CZ⁻¹ M_XB E_B M_BT x           (3.7)  actual TCP
    Δ  = P − P′                                 (3.11)
    Pᶜ = P + Δ                                  (3.12)
    xᶜ = M_BT⁻¹ E_B⁻¹ M_XB⁻¹ M_CZ E_C Pᶜ         (3.13)

with the first-order matrices of Eqs 3.8–3.10.  Step 3.13 inverts the *actual*
chain, which already removes the error; adding Δ in 3.12 as well corrects it a
second time: the actual TCP of the compensated command is A·xᶜ = P + Δ, so its
error is Δ = −(P′ − P), the error before with its sign turned.  The correct
step is xᶜ = A⁻¹ P (``corrected=True``).
"""

from __future__ import annotations

import numpy as np


def _E_B(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


def _E_C(theta):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def matrices(d: dict[str, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """M_CZ, M_XB, M_BT of Eqs 3.8–3.10 (first order), from deviations in mm/rad."""
    M_CZ = np.array([[1, 0, d["beta_CZ"], d["dx_CZ"]], [0, 1, -d["alpha_CZ"], d["dy_CZ"]],
                     [-d["beta_CZ"], d["alpha_CZ"], 1, 0], [0, 0, 0, 1.0]])
    M_XB = np.array([[1, -d["gamma_XB"], d["beta_XB"], 0], [d["gamma_XB"], 1, -d["alpha_XB"], 0],
                     [-d["beta_XB"], d["alpha_XB"], 1, 0], [0, 0, 0, 1.0]])
    M_BT = np.array([[1, 0, 0, d["dx_BT"]], [0, 1, -d["alpha_BT"], 0], [0, d["alpha_BT"], 1, d["dz_BT"]],
                     [0, 0, 0, 1.0]])
    return M_CZ, M_XB, M_BT


def actual_chain(d: dict[str, float], b_deg: float, c_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """(N, A): the ideal chain E_C⁻¹E_B (Eq 3.4) and the actual one E_C⁻¹M_CZ⁻¹M_XB E_B M_BT (Eq 3.7)."""
    M_CZ, M_XB, M_BT = matrices(d)
    E_B, E_Ci = _E_B(np.radians(b_deg)), np.linalg.inv(_E_C(np.radians(c_deg)))
    return E_Ci @ E_B, E_Ci @ np.linalg.inv(M_CZ) @ M_XB @ E_B @ M_BT


def compensate_thesis(d: dict[str, float], xyz: np.ndarray, bc_deg: np.ndarray,
                      corrected: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Commands ``(k, 3)`` by Eqs 3.4–3.13, and the TCP error before and after in the thesis' own chain.

    Returns ``(xyz_c, error_before, error_after)``, errors ``(k, 3)`` mm = A·x − P.
    ``corrected`` drops the Δ of Eq 3.12 (Pᶜ = P), which removes the error instead of turning it.
    """
    out, before, after = [], [], []
    for (X, Y, Z), (b, c) in zip(np.asarray(xyz, float), np.asarray(bc_deg, float)):
        N, A = actual_chain(d, b, c)
        x = np.array([X, Y, Z, 1.0])
        P, P_act = N @ x, A @ x
        P_c = P if corrected else P + (P - P_act)  # Eqs 3.11, 3.12
        x_c = np.linalg.solve(A, P_c)  # Eq 3.13: M_BT⁻¹ E_B⁻¹ M_XB⁻¹ M_CZ E_C Pᶜ = A⁻¹ Pᶜ
        out.append(x_c[:3])
        before.append((P_act - P)[:3])
        after.append((A @ x_c - P)[:3])
    return np.array(out), np.array(before), np.array(after)
