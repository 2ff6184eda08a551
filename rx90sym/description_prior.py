"""The robot's description as a prior: its bodies as written, made physical where they are not.

A description (a URDF's ``<inertial>`` elements, a robot file's ``[nominal]`` table) gives every
moving link a rigid body. It is a prior for the identification, never a gate: a body that no mass
distribution has loads, and each moving link gets a status:

- ``"physical"``: the body as written is the prior;
- ``"projected"``: as written it is not a physical rigid body (a principal moment below 0, the
  triangle inequality I_a + I_b >= I_c broken) but its mass is > 0: the prior is the nearest
  physical body with the same mass and centre of mass (rx90sym.physical.nearest_physical_body: the
  second moments about the centre of mass raised to rx90sym.physical.DEFAULT_MARGIN, the consistent
  fit's cone). Such a body is flat along one axis (a second moment at the margin): what it says
  about that axis is the least trustworthy part of the prior;
- ``"none"``: no inertial, a mass of 0, or a mass below 0 (no nearest body with that mass): the
  prior says nothing about the link (uninformative) and its ten inertial values in ``values`` are 0.

Links fixed to the ground (above the first movable joint: a URDF's ``base_link``) move nothing and
are ignored, with a note when their inertial is not physical. Rotor inertia and friction values
below 0 (a URDF's ``<dynamics>``) are 0 in the prior. :func:`description_warning` is the one
warning a load gives (every such link in one message); only the twin (``rx90 simulate`` with the
description's bodies) refuses them (:func:`simulation_refusal`). ``as_written`` keeps the values as
the file has them: the yardstick "the model the user had" uses those, not the prior.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

import numpy as np

from .description import Robot
from .physical import DEFAULT_MARGIN, NONNEGATIVE, body_problem, nearest_physical_body
from .rigid_body import RigidBody
from .urdf_carried import lumped_body
from .urdf_tree import zero_poses

__all__ = ["DescriptionPrior", "DescriptionWarning", "LinkPrior", "STATUSES", "description_prior",
           "description_warning", "required_description_prior", "simulation_refusal"]

#: A moving link's status in the prior (module docstring).
STATUSES = ("physical", "projected", "none")
_INERTIAL = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")


class DescriptionWarning(UserWarning):
    """A description whose bodies are not all physical: loaded, with the prior said (one per load)."""


@dataclass(frozen=True)
class LinkPrior:
    """One moving link of the prior.

    link: 1-based (Khalil link k, moved by joint k); name: the URDF link(s) it lumps, or "link k";
    status: "physical" | "projected" | "none"; mass: as written [kg]; problem: why the body as
    written is not physical ('' when it is); moments: principal moments about the centre of mass
    as written and in the prior [kg m^2] (empty for "none")."""

    link: int
    name: str
    status: str
    mass: float
    problem: str = ""
    moments: tuple[tuple[float, float, float], tuple[float, float, float]] | tuple[()] = ()

    def line(self) -> str:
        """The link's line in the warning ('' for a physical link, or a massless one as written)."""
        if self.status == "physical" or not self.problem:
            return ""
        if self.status == "none":
            return f"{self.name}: {self.problem}: no prior for this link (uninformative)"
        (a, b, c), (a1, b1, c1) = self.moments
        return (f"{self.name}: {self.problem}; prior = nearest physical body (moments {a:.4g}, {b:.4g}, {c:.4g} "
                f"-> {a1:.4g}, {b1:.4g}, {c1:.4g} kg m^2, same mass {self.mass:.4g} kg and centre of mass)")


@dataclass(frozen=True)
class DescriptionPrior:
    """The description's parameters as a prior (module docstring).

    source: what they come from (shown in outputs); values: theta_0, every standard parameter of the
    robot (name -> SI value, read-only), physical; as_written: the same names as the file gives them; links: one
    LinkPrior per moving link; ground: the links fixed to the ground whose inertial is ignored (not
    physical as written); notes: every line of the warning (also the ground links' and the
    friction values set to 0)."""

    source: str
    values: Mapping[str, float]
    as_written: Mapping[str, float]
    links: tuple[LinkPrior, ...]
    ground: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()

    @property
    def informative(self) -> bool:
        """Whether any moving link has a prior body (a status other than "none")."""
        return any(k.status != "none" for k in self.links)

    def status(self, link: int) -> str:
        """The status of moving link ``link`` (1-based)."""
        return self.links[link - 1].status

    def warning(self) -> str | None:
        """The warning text (None when every body is physical as written)."""
        return _warning_text(self.source, self.notes)


def _moments(body: RigidBody) -> tuple[float, float, float]:
    _, inertia = body.com_inertia()
    a, b, c = np.linalg.eigvalsh(inertia)
    return float(a), float(b), float(c)


def _judged(body: RigidBody) -> tuple[str, str, RigidBody]:
    """(status, problem, prior body) of one body as written (a massless all-zero body: "none", '')."""
    vector = body.vector()
    if not np.any(vector):
        return "none", "", body
    problem = body_problem(vector)
    if problem is None:
        return "physical", "", body
    if not body.m > DEFAULT_MARGIN:  # no body of that mass (a margin's worth of mass is none either)
        return "none", f"mass {body.m:.4g} kg is not > {0 if body.m <= 0 else DEFAULT_MARGIN:g}", RigidBody.zero()
    return "projected", problem, nearest_physical_body(body, DEFAULT_MARGIN)


def _with_margin(body: RigidBody) -> RigidBody:
    """A projected link's prior in its Khalil frame, physical with the consistent fit's margin there too
    (the projection holds it in the URDF link's frame; a frame change moves the cone's edge by ~the margin)."""
    return body if body_problem(body.vector(), DEFAULT_MARGIN) is None else nearest_physical_body(body, DEFAULT_MARGIN)


def _urdf_links(robot: Robot) -> tuple[list[LinkPrior], dict[int, RigidBody], list[str], list[str]]:
    """Per moving link: LinkPrior and the prior body in Khalil frame k (projected links only); the
    ground links whose inertial is not physical and their note lines."""
    chain = robot.urdf
    tree = chain.tree
    poses = zero_poses(tree)
    carried = {c for group in chain.lumped for c in group}
    judged = {name: _judged(body) for name, body in tree.inertials.items()}
    ground = [name for name in tree.inertials if name not in carried and judged[name][1]]
    notes = [f"link {name!r} is fixed to the ground (above the first joint): its inertial is ignored "
             f"({judged[name][1]})" for name in ground]
    links, bodies = [], {}
    for k, group in enumerate(chain.lumped):
        own = chain.links[k]
        bad = [c for c in group if judged[c][1]]
        label = (f"link {bad[0]!r} (joint {k + 1})" if bad == [own] else
                 f"link {own!r} (joint {k + 1}, carrying {', '.join(repr(c) for c in group if c != own)})"
                 if bad else f"link {own!r} (joint {k + 1})")
        problem = "; ".join(judged[c][1] if c == own else f"{c!r}: {judged[c][1]}" for c in bad)
        written = RigidBody.from_vector(np.array([chain.nominal[f"{p}{k + 1}"] for p in _INERTIAL]))
        if any(judged[c][0] == "none" for c in bad) or not written.m > 0:
            links.append(LinkPrior(k + 1, label, "none", float(written.m), problem))
        elif not bad:
            links.append(LinkPrior(k + 1, label, "physical", float(written.m)))
        else:
            prior = lumped_body(chain, poses, k, {c: judged[c][2] for c in group})
            bodies[k] = _with_margin(prior.expressed_in_child(*chain.link_to_khalil[k]))
            moments = ((_moments(tree.inertials[bad[0]]), _moments(judged[bad[0]][2])) if len(bad) == 1 else
                       (_moments(written), _moments(bodies[k])))
            links.append(LinkPrior(k + 1, label, "projected", float(written.m), problem, moments))
    return links, bodies, ground, notes


def _table_links(robot: Robot) -> tuple[list[LinkPrior], dict[int, RigidBody]]:
    """Per link of a robot file's [nominal] table: LinkPrior and the prior body (projected links only)."""
    links, bodies = [], {}
    for k in range(robot.n):
        body = robot.nominal.body(k)
        status, problem, prior = _judged(body)
        label = f"link {k + 1}"
        if status == "projected":
            bodies[k] = prior
            links.append(LinkPrior(k + 1, label, status, float(body.m), problem, (_moments(body), _moments(prior))))
        else:
            links.append(LinkPrior(k + 1, label, status, float(body.m), problem))
    return links, bodies


def _links(robot: Robot) -> tuple[list[LinkPrior], dict[int, RigidBody], list[str], list[str]] | None:
    if getattr(robot, "urdf", None) is not None:
        return _urdf_links(robot)
    if robot.nominal is not None:
        return (*_table_links(robot), [], [])
    return None


def description_warning(robot: Robot) -> str | None:
    """The one warning a load gives about the description's bodies (every link whose body as written is
    not physical, the ground links ignored), or None when all are physical. Needs only the bodies."""
    found = _links(robot)
    if found is None:
        return None
    links, _, _, notes = found
    return _warning_text(robot.source or robot.name, notes + [k.line() for k in links if k.line()])


def _warning_text(where: str, lines: list[str] | tuple[str, ...]) -> str | None:
    if not lines:
        return None
    return (f"{where}: the description's bodies are a prior, not all physical as written: " + "; ".join(lines)
            + " (the values as written are kept for comparison; rx90 simulate refuses them)")


def _written(robot: Robot) -> dict[str, float] | None:
    """The description's standard parameters as written (URDF inertials or the [nominal] table)."""
    if getattr(robot, "urdf", None) is not None:  # rx90sym.urdf_parameters: the lumped inertials as written
        return dict(robot.urdf.nominal)
    if robot.nominal is not None:
        from .nominal_table import NominalError, nominal_values

        try:
            return nominal_values(robot, robot.nominal)
        except NominalError as exc:
            raise ValueError(f"{robot.source or robot.name}: {exc}") from None
    return None


def description_prior(robot: Robot) -> DescriptionPrior | None:
    """The description's parameters as a prior (module docstring), or None when the robot has none
    (neither URDF inertials nor a [nominal] table). Raises ValueError naming the file when its
    [nominal] table does not fit the robot."""
    written = _written(robot)
    found = _links(robot)
    if written is None or found is None:
        return None
    links, bodies, ground, notes = found
    written = {name: written.get(name, 0.0) for name in robot.parameter_names}
    values = dict(written)
    for k, link in enumerate(links):
        if link.status == "none":
            values.update({f"{p}{k + 1}": 0.0 for p in _INERTIAL})
        elif k in bodies:
            values.update({f"{p}{k + 1}": float(v) for p, v in zip(_INERTIAL, bodies[k].vector())})
    lines = list(notes) + [k.line() for k in links if k.line()]
    negative = [name for name in robot.parameter_names if name.startswith(NONNEGATIVE) and values[name] < 0]
    if negative:
        lines.append(", ".join(f"{name} = {values[name]:.4g}" for name in negative) + " below 0 as written: 0 in the prior")
        values.update({name: 0.0 for name in negative})
    kind = "URDF inertials" if getattr(robot, "urdf", None) is not None else "[nominal] table"
    return DescriptionPrior(f"{kind} of {robot.source or robot.name}", MappingProxyType(values),
                            MappingProxyType(written), tuple(links), tuple(ground), tuple(lines))


def required_description_prior(robot: Robot, option: str = "--prior description") -> DescriptionPrior:
    """:func:`description_prior` where the description must be the prior (``option``): ValueError with
    the reason when the robot has no description parameters or every moving link's mass is 0."""
    prior = description_prior(robot)
    where = robot.source or robot.name
    if prior is None:
        raise ValueError(f"{option}: robot {robot.name!r} ({where}) has no description parameters (no URDF "
                         f"inertials, no [nominal] table): give a prior file (standard parameters, JSON) or none")
    if not prior.informative:
        masses = ", ".join(f"{k.mass:g}" for k in prior.links)
        raise ValueError(f"{option}: the description {where} gives no body to a moving link (masses {masses} kg): "
                         f"it cannot be the prior; give a prior file (standard parameters, JSON) or none")
    return prior


def simulation_refusal(robot: Robot) -> str | None:
    """Why the twin cannot simulate the description's own bodies (every moving link whose body as
    written is not physical, in one message), or None when it can."""
    found = _links(robot)
    if found is None:
        return None
    bad = [k for k in found[0] if k.problem]
    if not bad:
        return None
    return (f"{robot.source or robot.name}: the description's bodies are not physical rigid bodies, a simulator "
            f"cannot move them: " + "; ".join(f"{k.name}: {k.problem}" for k in bad))
