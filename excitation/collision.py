"""Self-collision and obstacle boxes: link capsules from the geometry.

Each link is a capsule (a segment and a radius) between consecutive distinct frame origins of the
forward geometric model, plus two fixed or tool segments:

- the base column, from the origin of frame 0 down ``base_length`` [m] along -z0;
- the links between consecutive distinct origins O_j -> O_j+1 (on the RX90: the upper arm
  O2 -> O3, 0.45 m, and the forearm O3 -> O4, 0.45 m; O1 = O2 and O4 = O5 = O6 coincide);
- the wrist and tool, from the last origin to the tool point (``tool_point`` [m] in frame n).

Radii (``CapsuleSet.radii``, in this order) default to DEFAULT_RADII scaled by the arm's reach
(sum of its |d| and |r|) over the RX90's 0.9 m: on the RX90 base 0.15 m, upper arm 0.10 m,
forearm 0.08 m, wrist and tool 0.06 m (its outer dimensions rounded up; extra links of other arms
0.08 m); on the TX40 (reach 0.485 m) 0.54 times these. Pairs of capsules that are not neighbours in the chain must not
touch (self-collision); when default capsules already touch at the centre of the joint ranges
(an arm with offsets such as a UR or a Panda: segments between frame origins do not describe its
links) self-collision is not checked, and this is reported (:func:`without_pairs_touching_at`);
no capsule may enter an obstacle box.

For IPOPT each capsule is covered by balls on its segment (at least ``spheres``, and at most one
radius r apart), radius sqrt(r^2 + (spacing/2)^2) so that the balls contain the capsule; each
pair of capsules (and each capsule and box) gives ONE smooth row, the soft minimum
-k log sum exp(-d/k) (k = SOFT_MIN) of its ball-pair clearances d (ball-centre distance minus
the inflated radii, or the box's signed distance minus the inflated radius): never above the true
minimum, so never optimistic. The optimiser imposes them on its constraint grid from the start,
merged into one soft minimum per sample (envelope_rows.py); :func:`capsule_clearances` gives the exact distances
for the check (segment-segment distance, box distance by a fine sampling of the segment).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Sequence

import casadi as ca
import numpy as np

from .kernels import evaluate_samples

if TYPE_CHECKING:  # for annotations only
    import rx90sym

DEFAULT_RADII = (0.15, 0.10, 0.08, 0.06)  # [m] for the RX90's reach REFERENCE_REACH
EXTRA_RADIUS = 0.08
REFERENCE_REACH = 0.9  # [m] RX90: d3 + r4


@dataclass(frozen=True)
class Box:
    """Axis-aligned obstacle box in frame 0 [m]: lower corner ``lo``, upper corner ``hi``."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]

    def __post_init__(self) -> None:
        lo, hi = np.asarray(self.lo, float), np.asarray(self.hi, float)
        if lo.shape != (3,) or hi.shape != (3,) or not np.all(np.isfinite(np.r_[lo, hi])):
            raise ValueError(f"obstacle box: corners must be 3 finite numbers each, got {self.lo}, {self.hi}")
        if np.any(hi <= lo):
            raise ValueError(f"obstacle box: max corner {tuple(hi)} must exceed min corner {tuple(lo)} "
                             f"on every axis")
        object.__setattr__(self, "lo", tuple(map(float, lo)))
        object.__setattr__(self, "hi", tuple(map(float, hi)))

    @staticmethod
    def parse(text: str) -> "Box":
        """From 'xmin,ymin,zmin,xmax,ymax,zmax' [m]."""
        try:
            v = [float(x) for x in text.split(",")]
        except ValueError:
            raise ValueError(f"obstacle box {text!r}: expected xmin,ymin,zmin,xmax,ymax,zmax in m") from None
        if len(v) != 6:
            raise ValueError(f"obstacle box {text!r}: expected 6 numbers, got {len(v)}")
        return Box(tuple(v[:3]), tuple(v[3:]))


@dataclass(frozen=True, eq=False)
class CapsuleSet:
    """The arm's capsules: ``segments`` casadi.Function q -> (3, 2k) end points [a_1 b_1 ...] in
    frame 0, ``radii`` (k,) [m], ``names``; ``pairs``: capsules that must not touch; ``ignored``:
    pairs left out because they touch in the reference pose (:func:`without_pairs_touching_at`)."""

    segments: ca.Function
    radii: tuple[float, ...]
    names: tuple[str, ...]
    pairs: tuple[tuple[int, int], ...]
    ignored: tuple[tuple[int, int], ...] = ()
    links: tuple[int, ...] = ()  # Khalil frame each capsule is fixed in (0: base); () unknown
    never: tuple[tuple[int, int], ...] = ()  # pairs never near in random poses: checked exactly, not in IPOPT's cover

    def pair_names(self, pairs: Sequence[tuple[int, int]]) -> list[str]:
        """'a / b' for each pair of capsule indices."""
        return [f"{self.names[i]} / {self.names[j]}" for i, j in pairs]


def without_pairs_touching_at(capsules: CapsuleSet, q: Sequence[float], every: bool = False) -> CapsuleSet:
    """``capsules`` without the pairs that already touch at the joint values ``q`` [rad] (the centre
    of the joint ranges): with default radii on an arm they do not fit (a UR's offset wrist, a
    Panda's compact links), such a pair is in contact by construction and would forbid every
    motion. MoveIt's setup assistant disables pairs "in collision by default" the same way. The
    pairs left out are kept in ``ignored`` so that callers can say so. every: leave out every pair
    (none is checked) if one touches."""
    q = np.asarray(q, dtype=float)[None, :]
    ends = np.asarray(capsules.segments(q.T)).reshape(3, -1, order="F")
    a, b = ends[:, 0::2], ends[:, 1::2]
    touching = []
    for i, j in capsules.pairs:
        d = _segment_distance(a[:, i][None], b[:, i][None], a[:, j][None], b[:, j][None])[0]
        if d - capsules.radii[i] - capsules.radii[j] < 0.0:
            touching.append((i, j))
    if not touching:
        return capsules
    if every:
        touching = list(capsules.pairs)
    kept = tuple(p for p in capsules.pairs if p not in touching)
    return CapsuleSet(capsules.segments, capsules.radii, capsules.names, kept,
                      capsules.ignored + tuple(touching), capsules.links)


def arm_capsules(robot: rx90sym.Robot, tool_point: Sequence[float] = (0.0, 0.0, 0.1), base_length: float = 0.5,
                 radii: Sequence[float] | None = None) -> CapsuleSet:
    """Capsules of ``robot`` (see the module docstring); tool_point [m] in frame n."""
    n = robot.n
    q = ca.SX.sym("q", n)
    t0n, origins = robot.forward_kinematics(q)
    probe = ca.Function("origins", [q], [origins])
    rng = np.random.default_rng(0)
    samples = [np.asarray(probe(rng.uniform(-2, 2, n))) for _ in range(3)]
    kept: list[int] = []  # origins that differ (for random q) from the previous kept point
    for j in range(n):
        if any(np.linalg.norm(smp[:, j] - (smp[:, kept[-1]] if kept else 0.0)) > 1e-9 for smp in samples):
            kept.append(j)
    points = [ca.DM([0.0, 0.0, -base_length]), ca.DM.zeros(3)] + [origins[:, j] for j in kept]
    names = ["base"] + [f"link to frame {j + 1}" for j in kept]
    links = [0] + kept  # O_j+1 is fixed in frame j, and so is the previous kept origin
    tool = ca.mtimes(t0n, ca.DM([*tool_point, 1.0]))[:3]
    points.append(tool)
    names.append("wrist and tool")
    links.append(n)
    k = len(points) - 1
    ends = ca.horzcat(*[ca.horzcat(points[i], points[i + 1]) for i in range(k)])
    if radii is None:
        # Scaled down for smaller arms; never up: a longer arm (a cobot) is not fatter than the RX90.
        scale = min(1.0, (float(np.sum(np.abs(robot.d)) + np.sum(np.abs(robot.r))) / REFERENCE_REACH) or 1.0)
        radii = tuple(scale * (DEFAULT_RADII[i] if i < len(DEFAULT_RADII) - 1 else EXTRA_RADIUS)
                      for i in range(k - 1)) + (scale * DEFAULT_RADII[-1],)
    radii = tuple(float(r) for r in radii)
    if len(radii) != k or any(r <= 0 for r in radii):
        raise ValueError(f"capsules: {k} positive radii needed ({', '.join(names)}), got {radii}")
    pairs = tuple((i, j) for i in range(k) for j in range(i + 2, k))
    return CapsuleSet(ca.Function("capsules", [q], [ends], ["q"], ["ends"]), radii, tuple(names), pairs,
                      links=tuple(links))


def _box_distance(p: Any, box: Box) -> Any:
    """Signed distance [m] of point p (3,) to the box (negative inside), CasADi or numpy."""
    c = 0.5 * (np.asarray(box.lo) + np.asarray(box.hi))
    h = 0.5 * (np.asarray(box.hi) - np.asarray(box.lo))
    if isinstance(p, (ca.SX, ca.MX)):
        d = ca.fabs(p - ca.DM(c)) - ca.DM(h)
        outside = ca.sqrt(ca.sumsqr(ca.fmax(d, 0.0)) + 1e-12)
        return outside + ca.fmin(ca.mmax(d), 0.0)
    d = np.abs(np.asarray(p) - c) - h
    return np.linalg.norm(np.maximum(d, 0.0), axis=-1) + np.minimum(np.max(d, axis=-1), 0.0)


def clearance_function(capsules: CapsuleSet, boxes: Sequence[Box] = (), self_collision: bool = True,
                       spheres: int = 5) -> ca.Function | None:
    """casadi.Function q -> clearances (k,) [m] that must stay >= 0 (ball cover, see module
    docstring); None when there is nothing to keep apart."""
    if spheres < 2:
        raise ValueError(f"capsules: spheres must be >= 2, got {spheres}")
    n = capsules.segments.size1_in(0)
    q = ca.SX.sym("q", n)
    ends = capsules.segments(q)
    rest = np.asarray(capsules.segments(np.zeros(n)))  # (3, 2k): [a_1 b_1 a_2 b_2 ...]
    lengths = np.linalg.norm(rest[:, 1::2] - rest[:, 0::2], axis=0)
    k = len(capsules.radii)
    balls = []  # (centres list, inflated radius) per capsule
    for i in range(k):
        # Balls at most one radius apart (half-spacing <= r): the inflated radius
        # sqrt(r^2 + (spacing/2)^2) then exceeds r by at most 41 %, not 100 % (a small arm's long
        # base column would otherwise forbid its own range centre).
        m_i = max(spheres, int(np.ceil(lengths[i] / capsules.radii[i])) + 1)
        a, b = ends[:, 2 * i], ends[:, 2 * i + 1]
        centres = [a + (b - a) * (m / (m_i - 1)) for m in range(m_i)]
        spacing = ca.norm_2(b - a) / (m_i - 1)
        balls.append((centres, ca.sqrt(capsules.radii[i] ** 2 + (0.5 * spacing) ** 2)))
    rows = []
    if self_collision:
        for i, j in capsules.pairs:
            if (i, j) in capsules.never:
                continue
            (ci, ri), (cj, rj) = balls[i], balls[j]
            rows.append(_soft_min([ca.norm_2(x - y) - ri - rj for x in ci for y in cj]))
    for box in boxes:
        for centres, r in balls:
            rows.append(_soft_min([_box_distance(c, box) - r for c in centres]))
    if not rows:
        return None
    return ca.Function("clearances", [q], [ca.vertcat(*rows)], ["q"], ["clearance"])


SOFT_MIN = 0.002  # [m] temperature of the smooth minimum over ball pairs


def _soft_min(values: list) -> ca.SX:
    """Smooth minimum -k log sum exp(-v / k) (k = SOFT_MIN): one smooth row per capsule pair,
    never above the true minimum (so never optimistic) and at most k log(count) below it."""
    if len(values) == 1:
        return values[0]
    v = ca.vertcat(*values)
    return -SOFT_MIN * ca.logsumexp(-v / SOFT_MIN)


def _segment_distance(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Shortest distance between segments [p1, q1] and [p2, q2], vectorised over rows (N, 3)."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f = np.sum(d1 * d1, -1), np.sum(d2 * d2, -1), np.sum(d2 * r, -1)
    c, b = np.sum(d1 * r, -1), np.sum(d1 * d2, -1)
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 1e-12, np.clip((b * f - c * e) / denom, 0, 1), 0.0)
        t = np.where(e > 1e-12, (b * s + f) / e, 0.0)
        s = np.where(t < 0, np.where(a > 1e-12, np.clip(-c / a, 0, 1), 0.0), s)
        s = np.where(t > 1, np.where(a > 1e-12, np.clip((b - c) / a, 0, 1), 0.0), s)
    t = np.clip(t, 0, 1)
    return np.linalg.norm((p1 + d1 * s[:, None]) - (p2 + d2 * t[:, None]), axis=-1)


def capsule_clearances(capsules: CapsuleSet, q: np.ndarray, boxes: Sequence[Box] = (),
                       self_collision: bool = True, box_samples: int = 50) -> np.ndarray:
    """Exact clearance [m] per sample (N,): the smallest over capsule pairs of segment distance
    minus both radii, and over capsules and boxes of the box distance (segment sampled at
    ``box_samples`` points) minus the radius. Negative: the capsules touch."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    ends = evaluate_samples(capsules.segments, q).transpose(1, 2, 0)  # (3, 2k, N)
    a, b = ends[:, 0::2, :], ends[:, 1::2, :]  # (3, k, N)
    out = np.full(q.shape[0], np.inf)
    if self_collision:
        for i, j in capsules.pairs:
            d = _segment_distance(a[:, i].T, b[:, i].T, a[:, j].T, b[:, j].T)
            out = np.minimum(out, d - capsules.radii[i] - capsules.radii[j])
    s = np.linspace(0.0, 1.0, box_samples)
    for box in boxes:
        for i, r in enumerate(capsules.radii):
            pts = a[:, i].T[:, None, :] + (b[:, i] - a[:, i]).T[:, None, :] * s[None, :, None]
            out = np.minimum(out, np.min(_box_distance(pts, box), axis=1) - r)
    return out


@dataclass(frozen=True, eq=False)
class CollisionModel:
    """What must not touch: the arm's capsules among themselves (``self_collision``) and the
    obstacle ``boxes``; ``clearance`` is the smooth ball-cover function for IPOPT, :meth:`exact`
    the check."""

    capsules: CapsuleSet
    boxes: tuple[Box, ...] = ()
    self_collision: bool = True
    spheres: int = 3  # at least 3 balls per capsule: half the instructions of 5, a few mm of clearance less

    def __post_init__(self) -> None:
        object.__setattr__(self, "boxes", tuple(self.boxes))
        object.__setattr__(self, "_clearance",
                           clearance_function(self.capsules, self.boxes, self.self_collision, self.spheres))

    @property
    def clearance(self) -> ca.Function | None:
        """casadi.Function q -> (k,) clearances [m] >= 0 required, or None."""
        return self._clearance  # type: ignore[attr-defined]

    def exact(self, q: np.ndarray) -> np.ndarray:
        """Exact smallest clearance [m] per sample (N,) (see :func:`capsule_clearances`)."""
        return capsule_clearances(self.capsules, q, self.boxes, self.self_collision)
