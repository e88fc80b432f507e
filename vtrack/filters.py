"""Linear Kalman filtering with the motion models of the documents (S0, S2, S4).

The shape follows Stone Soup's split of a tracker's filter into a transition model and a
predictor/updater on immutable Gaussian states: a :class:`MotionModel` knows its matrices for a
time step ``dt`` and predicts a :class:`GaussianState` by ``dt`` (:meth:`MotionModel.predict`)
or corrects it with a measured point (:meth:`MotionModel.update`); nothing is re-timed in
place. The three models of the documents, by name in :data:`MOTION_MODELS`
(:func:`motion_model` builds one):

- ``cv``, :class:`ConstantVelocity` - S0 (Liu et al. 2022, sec. 3, eq. 8-17): per axis
  ``(x, dx)``;
- ``ca``, :class:`ConstantAcceleration` - S2 (Di & Zhu 2008, sec. 5, eq. 14-16): per axis
  ``(x, v, a)``, started from the first three positions;
- ``gravity``, :class:`Gravity` - S4 (Gan 2018, sec. 3, eq. 11-13): ``(x, y, ux, vy)`` with a
  gravity input.

Every model measures a point ``(x, y)`` (a box centre), and :meth:`MotionModel.position` is a
state's ``(x, y)``, so a tracker can hold one state per target whatever the model.

S0 and S2 filter each axis independently. Their two per-axis filters are run here as one
block-diagonal filter (state ``(x, dx, y, dy)`` or ``(x, vx, ax, y, vy, ay)``): every matrix
is ``I2 (x) M`` for the per-axis ``M``, so the numbers are exactly those of two separate
filters, at half the Python overhead.

Time is counted in ``dt`` units; with ``dt = 1`` (the documents' frame step) velocities are in
pixels per frame. A model keeps the matrices of the last step it was asked for and reuses them
for a step equal up to timestamp rounding (``i / fps`` timestamps differ in their last bits).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

Point = tuple[float, float]


def _is_diagonal(S: np.ndarray) -> bool:
    """Whether the square matrix ``S`` has only zeros off its diagonal (checked on Python floats:
    cheaper than NumPy calls on a 2 x 2)."""
    rows = S.tolist()
    return all(value == 0.0 for i, row in enumerate(rows) for j, value in enumerate(row) if i != j)


def same_step(a: float, b: float | None) -> bool:
    """Whether two time steps are the same up to timestamp rounding."""
    return b is not None and math.isclose(a, b, rel_tol=1e-6)


@dataclass(frozen=True)
class GaussianState:
    """A state estimate ``x`` with its covariance ``P`` (never changed in place)."""

    x: np.ndarray
    P: np.ndarray


class MotionModel(ABC):
    """A linear motion model measured as a point: ``x' = F(dt) x + B(dt) u + w`` (``w ~ Q``),
    ``z = H x + v`` (``v ~ R``); ``u`` a constant control input (None: none)."""

    #: Name in configs (``model = "cv"``).
    name: ClassVar[str]
    #: Measured positions needed to start a state (:meth:`initiate`).
    points: ClassVar[int] = 1

    H: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    u: np.ndarray | None = None

    def __init__(self) -> None:
        self._dt: float | None = None
        self._matrices: tuple[np.ndarray, np.ndarray | None] | None = None

    @abstractmethod
    def matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray | None]:
        """The state transition ``F`` and control matrix ``B`` (None: no input) for ``dt``."""

    @abstractmethod
    def initiate(self, points: Sequence[Point], dt: float = 1.0) -> GaussianState:
        """The first state, from the first :attr:`points` measured positions."""

    def transition(self, dt: float) -> tuple[np.ndarray, np.ndarray | None]:
        """:meth:`matrices` for ``dt``; the last step's when ``dt`` equals it up to rounding."""
        matrices = self._matrices
        if matrices is None or (dt != self._dt and not same_step(dt, self._dt)):
            self._dt = dt
            matrices = self._matrices = self.matrices(dt)
        return matrices

    def predict(self, state: GaussianState, dt: float,
                Q: np.ndarray | None = None) -> GaussianState:
        """The state ``dt`` later. S0 eq. 10-11 / S4 eq. 5-6: ``x = F x + B u``,
        ``P = F P F^T + Q`` (with the process noise ``Q`` of this step; default: the
        model's)."""
        F, B = self.transition(dt)
        x = F @ state.x
        if B is not None and self.u is not None:
            x += B @ self.u
        return GaussianState(x, F @ state.P @ F.T + (self.Q if Q is None else Q))

    def update(self, state: GaussianState, z: Sequence[float] | np.ndarray,
               R: np.ndarray | None = None) -> GaussianState:
        """``state`` corrected by the measured point ``z`` (with the measurement noise ``R`` of
        this measurement; default: the model's).

        S0 eq. 13-17 / S4 eq. 7-10: ``K = P H^T (H P H^T + R)^-1``, ``x = x + K (z - H x)``,
        ``P = (I - K H) P``.
        """
        H, P = self.H, state.P
        PHt = P @ H.T
        S = H @ PHt + (self.R if R is None else R)
        # In the three models the measured coordinates are independent (per-axis blocks,
        # diagonal R), so S is diagonal and S^-1 is the reciprocal of its diagonal: the same
        # numbers as np.linalg.inv, without a general inversion every frame.
        gain = PHt * (1.0 / np.diagonal(S)) if _is_diagonal(S) else PHt @ np.linalg.inv(S)
        x = state.x + gain @ (np.asarray(z, np.float64) - H @ state.x)
        return GaussianState(x, P - gain @ H @ P)

    def position(self, state: GaussianState) -> Point:
        """The measured quantity of ``state``, ``H x``, as an ``(x, y)`` point."""
        px, py = self.H @ state.x
        return float(px), float(py)


def _axis_transition(model: str, dt: float, kinematic: bool = False) -> np.ndarray:
    """One axis's state transition for a step of ``dt``: S0 eq. 8 (``cv``), S2 eq. 14 (``ca``)."""
    if model == "cv":
        return np.array([[1.0, dt], [0.0, 1.0]])
    square = dt * dt / 2 if kinematic else dt * dt  # S2 eq. 14 prints T^2
    return np.array([[1.0, dt, square], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])


_PAIR = np.eye(2)


#: Positions of dx and dy in a constant-velocity state ``(x, dx, y, dy)``.
_CV_VELOCITY = [1, 3]


class ConstantVelocity(MotionModel):
    """S0 sec. 3, eq. 8-17: per axis state ``(x, dx)``, started at the first point at rest.

    S0 eq. 8-9: ``F = [[1, dt], [0, 1]]`` (the paper's ``dt = 1`` frame), ``H = [1, 0]``;
    S0 eq. 11, 13: ``Q = q I`` and ``R = r`` (the paper: ``Q = I``, ``R = 1``). The initial
    covariance is not given: ``P0 = p0 I`` (large, so the first measurements dominate).
    """

    name = "cv"

    def __init__(self, q: float = 1.0, r: float = 1.0, p0: float = 100.0) -> None:
        super().__init__()
        self.H = np.kron(_PAIR, np.array([[1.0, 0.0]]))
        self.Q = np.kron(_PAIR, q * np.eye(2))
        self.R = r * _PAIR
        self.P0 = np.kron(_PAIR, p0 * np.eye(2))

    def matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray | None]:
        return np.kron(_PAIR, _axis_transition("cv", dt)), None

    def initiate(self, points: Sequence[Point], dt: float = 1.0) -> GaussianState:
        x, y = points[0]
        return GaussianState(np.array([x, 0.0, y, 0.0]), self.P0)

    def velocity(self, state: GaussianState) -> np.ndarray:
        """The ``(dx, dy)`` of ``state`` (a new array)."""
        return state.x[_CV_VELOCITY].copy()

    def with_velocity(self, state: GaussianState, velocity: np.ndarray) -> GaussianState:
        """``state`` with its velocity replaced by ``velocity`` (covariance unchanged)."""
        x = state.x.copy()
        x[_CV_VELOCITY] = velocity
        return GaussianState(x, state.P)


class ConstantAcceleration(MotionModel):
    """S2 sec. 5: per axis ``(position, velocity, acceleration)`` from the first three points.

    S2 eq. 14-16: ``A = [[1, T, T^2], [0, 1, T], [0, 0, 1]]`` as printed (``kinematic``: the
    textbook ``T^2 / 2``), ``C = [1, 0, 0]``, ``R = r`` (S2: ``sigma_r^2 = 1``),
    ``W = diag(0, 0, q)`` (S2: ``sigma_w^2 = 1``). The state is started at the third point:
    ``S3 = [x3, (x3 - x2)/T, (x3 - 2 x2 + x1)/T^2]``, with the document's ``V3``; both are the
    linear map ``J`` from ``(x1, x2, x3)`` to ``S3`` and ``V3 = r J J^T + W``. As printed, ``v``
    is the backward difference and ``x + T v + T^2 a`` extrapolates a parabola exactly. With
    ``kinematic``, ``v`` is the parabola's velocity at the third point,
    ``(3 x3 - 4 x2 + x1) / (2T)``, so that ``x + T v + T^2 a / 2`` is exact too.
    """

    name = "ca"
    points = 3

    def __init__(self, q: float = 1.0, r: float = 1.0, kinematic: bool = False) -> None:
        super().__init__()
        self.q, self.r, self.kinematic = q, r, kinematic
        self.H = np.kron(_PAIR, np.array([[1.0, 0.0, 0.0]]))
        self.W = np.diag([0.0, 0.0, q])
        self.Q = np.kron(_PAIR, self.W)
        self.R = r * _PAIR

    def matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray | None]:
        return np.kron(_PAIR, _axis_transition("ca", dt, self.kinematic)), None

    def initiate(self, points: Sequence[Point], dt: float = 1.0) -> GaussianState:
        if len(points) != 3:
            raise ValueError(f"the ca model starts from three points, got {len(points)}")
        T, r = dt, self.r
        velocity = ([1 / (2 * T), -4 / (2 * T), 3 / (2 * T)] if self.kinematic
                    else [0.0, -1 / T, 1 / T])
        J = np.array([[0.0, 0.0, 1.0], velocity, [1 / T**2, -2 / T**2, 1 / T**2]])
        V3 = r * J @ J.T + self.W  # S2: the document's V3 (as printed) for kinematic = False
        track = np.asarray(points, np.float64)  # rows: frames 1, 2, 3; columns: x, y
        return GaussianState(np.concatenate([J @ track[:, 0], J @ track[:, 1]]),
                             np.kron(_PAIR, V3))


class Gravity(MotionModel):
    """S4 sec. 3, eq. 11-13: state ``(x, y, ux, vy)``, constant velocity plus gravity.

    S4 eq. 11: ``X(k+1) = A X(k) + B u`` with ``A`` the constant-velocity matrix for step
    ``dt`` and the gravity input on the vertical velocity, ``B u = (0, 0, 0, g dt)`` (the
    paper prints ``g/dt``; the two agree at the default ``dt = 1``, ``g dt`` is the
    kinematic one). ``y`` grows downwards, so ``g > 0`` pulls down. S4 eq. 12: ``H`` picks
    ``(x, y)``. S4 eq. 13: ``P(1) = p0 I`` (the paper: 100 I). Q and R are not given in the
    paper: ``Q = q I``, ``R = r I``. Started at the first point at rest.
    """

    name = "gravity"

    def __init__(self, q: float = 1.0, r: float = 1.0, p0: float = 100.0,
                 g: float = 1.0) -> None:
        super().__init__()
        self.H = np.eye(2, 4)
        self.Q = q * np.eye(4)
        self.R = r * np.eye(2)
        self.P0 = p0 * np.eye(4)
        self.u = np.array([g], np.float64)

    def matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray | None]:
        A = np.eye(4)
        A[0, 2] = A[1, 3] = dt
        return A, np.array([[0.0], [0.0], [0.0], [dt]])

    def initiate(self, points: Sequence[Point], dt: float = 1.0) -> GaussianState:
        x, y = points[0]
        return GaussianState(np.array([x, y, 0.0, 0.0]), self.P0)


#: The motion models by config name.
MOTION_MODELS: dict[str, type[MotionModel]] = {
    m.name: m for m in (ConstantVelocity, ConstantAcceleration, Gravity)
}


def motion_model(name: str, q: float = 1.0, r: float = 1.0, p0: float = 100.0,
                 kinematic: bool = False, g: float = 1.0) -> MotionModel:
    """The model ``name`` (:data:`MOTION_MODELS`) with the parameters it uses (the others are
    ignored: ``p0`` is not the ca model's, ``kinematic`` only ca's, ``g`` only gravity's)."""
    makers: dict[str, Callable[[], MotionModel]] = {
        "cv": lambda: ConstantVelocity(q, r, p0),
        "ca": lambda: ConstantAcceleration(q, r, kinematic),
        "gravity": lambda: Gravity(q, r, p0, g),
    }
    return makers[name]()
