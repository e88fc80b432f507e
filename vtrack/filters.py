"""Linear Kalman filters and the motion models of the documents (S0, S2, S4).

:class:`KalmanFilter` is the textbook filter (``predict(u)`` / ``update(z)``) on small NumPy
matrices. The constructors build the three point-motion models of ``ALGORITHMS.md``; each
returns a filter whose measurement is a point ``(x, y)`` (a box centre) and whose
:meth:`KalmanFilter.position` is the filter's current ``(x, y)``, so a tracker can hold one per
target whatever the model:

- :func:`constant_velocity` - S0 item 6 (Liu et al. 2022, eq. 8-17): per axis ``(x, dx)``;
- :func:`constant_acceleration` - S2 item 8 (Di & Zhu 2008, eq. 14-16): per axis
  ``(x, v, a)``, started from the first three positions;
- :func:`gravity` - S4 item 3 (Gan 2018, eq. 11-13): ``(x, y, ux, vy)`` with a gravity input.

S0 and S2 filter each axis independently. Their two per-axis filters are run here as one
block-diagonal filter (state ``(x, dx, y, dy)`` or ``(x, vx, ax, y, vy, ay)``): every matrix
is ``I2 (x) M`` for the per-axis ``M``, so the numbers are exactly those of two separate
filters, at half the Python overhead.

Time is counted in ``dt`` units; with ``dt = 1`` (the documents' frame step) velocities are in
pixels per frame. :func:`transition` gives a model's matrices for another step, so a filter can
follow the actual time between frames (``filter.F, filter.B = transition(...)``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

Point = tuple[float, float]


def _is_diagonal(S: np.ndarray) -> bool:
    """Whether the square matrix ``S`` has only zeros off its diagonal (checked on Python floats:
    cheaper than NumPy calls on a 2 x 2)."""
    rows = S.tolist()
    return all(value == 0.0 for i, row in enumerate(rows) for j, value in enumerate(row) if i != j)


class KalmanFilter:
    """A linear Kalman filter ``x' = F x + B u + w``, ``z = H x + v`` (``w ~ Q``, ``v ~ R``).

    ``x`` is the state estimate and ``P`` its covariance; ``u`` is a constant control input used
    when :meth:`predict` is called without one (None: no input).
    """

    __slots__ = ("F", "H", "Q", "R", "B", "u", "x", "P")

    def __init__(
        self,
        F: np.ndarray,
        H: np.ndarray,
        Q: np.ndarray,
        R: np.ndarray,
        x: np.ndarray,
        P: np.ndarray,
        B: np.ndarray | None = None,
        u: np.ndarray | None = None,
    ) -> None:
        self.F = np.asarray(F, np.float64)
        self.H = np.asarray(H, np.float64)
        self.Q = np.asarray(Q, np.float64)
        self.R = np.asarray(R, np.float64)
        self.x = np.asarray(x, np.float64)
        self.P = np.asarray(P, np.float64)
        self.B = None if B is None else np.asarray(B, np.float64)
        self.u = None if u is None else np.asarray(u, np.float64)

    def predict(self, u: np.ndarray | None = None) -> np.ndarray:
        """Advance one step and return the prior state.

        S0 eq. 10-11 / S4 eq. 5-6: ``x = F x + B u``, ``P = F P F^T + Q``.
        """
        control = self.u if u is None else np.asarray(u, np.float64)
        self.x = self.F @ self.x
        if self.B is not None and control is not None:
            self.x += self.B @ control
        self.P = self.F @ self.P @ self.F.T + self.Q
        return self.x

    def update(self, z: Sequence[float] | np.ndarray) -> np.ndarray:
        """Correct the state with the measurement ``z`` and return the posterior state.

        S0 eq. 13-17 / S4 eq. 7-10: ``K = P H^T (H P H^T + R)^-1``, ``x = x + K (z - H x)``,
        ``P = (I - K H) P``.
        """
        PHt = self.P @ self.H.T
        S = self.H @ PHt + self.R
        # In the three models the measured coordinates are independent (per-axis blocks,
        # diagonal R), so S is diagonal and S^-1 is the reciprocal of its diagonal: the same
        # numbers as np.linalg.inv, without a general inversion every frame.
        gain = PHt * (1.0 / np.diagonal(S)) if _is_diagonal(S) else PHt @ np.linalg.inv(S)
        self.x = self.x + gain @ (np.asarray(z, np.float64) - self.H @ self.x)
        self.P = self.P - gain @ self.H @ self.P
        return self.x

    def position(self) -> Point:
        """The measured quantity of the current state, ``H x``, as an ``(x, y)`` point."""
        px, py = self.H @ self.x
        return float(px), float(py)


def _per_axis(
    F: np.ndarray, H: np.ndarray, Q: np.ndarray, R: float, P: np.ndarray, xs: np.ndarray,
    ys: np.ndarray,
) -> KalmanFilter:
    """One block-diagonal filter running the per-axis model ``(F, H, Q, R, P)`` on x and y."""
    pair = np.eye(2)
    return KalmanFilter(
        F=np.kron(pair, F),
        H=np.kron(pair, H),
        Q=np.kron(pair, Q),
        R=R * pair,
        x=np.concatenate([xs, ys]),
        P=np.kron(pair, P),
    )


def constant_velocity(
    point: Point, q: float = 1.0, r: float = 1.0, p0: float = 100.0, dt: float = 1.0
) -> KalmanFilter:
    """S0 item 6: per axis state ``(x, dx)``, started at ``point`` at rest.

    S0 eq. 8-9: ``F = [[1, dt], [0, 1]]`` (the paper's ``dt = 1`` frame), ``H = [1, 0]``;
    S0 eq. 11, 13: ``Q = q I`` and ``R = r`` (the paper: ``Q = I``, ``R = 1``). The initial
    covariance is not given: ``P0 = p0 I`` (large, so the first measurements dominate).
    """
    F = _axis_transition("cv", dt)
    H = np.array([[1.0, 0.0]])
    x, y = point
    return _per_axis(F, H, q * np.eye(2), r, p0 * np.eye(2), np.array([x, 0.0]),
                     np.array([y, 0.0]))


def constant_acceleration(
    points: Sequence[Point], q: float = 1.0, r: float = 1.0, dt: float = 1.0,
    kinematic: bool = False,
) -> KalmanFilter:
    """S2 item 8: per axis ``(position, velocity, acceleration)`` from the first three points.

    S2 eq. 14-16: ``A = [[1, T, T^2], [0, 1, T], [0, 0, 1]]`` as printed (``kinematic``: the
    textbook ``T^2 / 2``), ``C = [1, 0, 0]``, ``R = r`` (S2: ``sigma_r^2 = 1``),
    ``W = diag(0, 0, q)`` (S2: ``sigma_w^2 = 1``). The state is started at the third point:
    ``S3 = [x3, (x3 - x2)/T, (x3 - 2 x2 + x1)/T^2]``, with the document's ``V3``; both are the
    linear map ``J`` from ``(x1, x2, x3)`` to ``S3`` and ``V3 = r J J^T + W``. As printed, ``v``
    is the backward difference and ``x + T v + T^2 a`` extrapolates a parabola exactly. With
    ``kinematic``, ``v`` is the parabola's velocity at the third point,
    ``(3 x3 - 4 x2 + x1) / (2T)``, so that ``x + T v + T^2 a / 2`` is exact too.
    """
    if len(points) != 3:
        raise ValueError(f"constant_acceleration needs the first three points, got {len(points)}")
    T = dt
    F = _axis_transition("ca", T, kinematic)
    H = np.array([[1.0, 0.0, 0.0]])
    W = np.diag([0.0, 0.0, q])
    velocity = [1 / (2 * T), -4 / (2 * T), 3 / (2 * T)] if kinematic else [0.0, -1 / T, 1 / T]
    J = np.array([[0.0, 0.0, 1.0], velocity, [1 / T**2, -2 / T**2, 1 / T**2]])
    V3 = r * J @ J.T + W  # S2: the document's V3 (as printed) for kinematic = False
    track = np.asarray(points, np.float64)  # rows: frames 1, 2, 3; columns: x, y
    return _per_axis(F, H, W, r, V3, J @ track[:, 0], J @ track[:, 1])


def gravity(
    point: Point, q: float = 1.0, r: float = 1.0, p0: float = 100.0, dt: float = 1.0,
    g: float = 1.0,
) -> KalmanFilter:
    """S4 item 3: state ``(x, y, ux, vy)`` at ``point``, constant velocity plus gravity.

    S4 eq. 11: ``X(k+1) = A X(k) + B u`` with ``A`` the constant-velocity matrix for step
    ``dt`` and the gravity input on the vertical velocity, ``B u = (0, 0, 0, g dt)`` (the
    paper prints ``g/dt``; the two agree at the default ``dt = 1``, ``g dt`` is the
    kinematic one). ``y`` grows downwards, so ``g > 0`` pulls down. S4 eq. 12: ``H`` picks
    ``(x, y)``. S4 eq. 13: ``P(1) = p0 I`` (the paper: 100 I). Q and R are not given in the
    paper: ``Q = q I``, ``R = r I``.
    """
    A, B = transition("gravity", dt)
    H = np.eye(2, 4)
    x, y = point
    return KalmanFilter(
        F=A, H=H, Q=q * np.eye(4), R=r * np.eye(2), x=np.array([x, y, 0.0, 0.0]),
        P=p0 * np.eye(4), B=B, u=np.array([g]),
    )


def _axis_transition(model: str, dt: float, kinematic: bool = False) -> np.ndarray:
    """One axis's state transition for a step of ``dt``: S0 eq. 8 (``cv``), S2 eq. 14 (``ca``)."""
    if model == "cv":
        return np.array([[1.0, dt], [0.0, 1.0]])
    square = dt * dt / 2 if kinematic else dt * dt  # S2 eq. 14 prints T^2
    return np.array([[1.0, dt, square], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])


def transition(
    model: str, dt: float, kinematic: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    """The state transition ``F`` and control matrix ``B`` (None without one) of the filter that
    :func:`constant_velocity` (``"cv"``), :func:`constant_acceleration` (``"ca"``) or
    :func:`gravity` (``"gravity"``) builds, for a step of ``dt``."""
    if model == "gravity":
        A = np.eye(4)
        A[0, 2] = A[1, 3] = dt
        return A, np.array([[0.0], [0.0], [0.0], [dt]])
    return np.kron(np.eye(2), _axis_transition(model, dt, kinematic)), None
