"""A rod twisted with both ends held: inputs, energy and constraints.

The framed Kirchhoff rod (``jaxrod.discretise.framed``; inextensible, unshearable, length L,
bending stiffnesses B1 <= or >= B2, twist stiffness C) is clamped at s = 0 and, at s = 1, held
by a second clamp that keeps the far end on the rod's axis e3 with its frame turned by
``turns`` about it. In units of B1 and L the energy is

    E = 1/2 int_0^1 (u1^2 + beta u2^2 + gamma u3^2) ds - t int_0^1 d3 . e3 ds,

beta = B2 / B1, gamma = C / B1 (``twist_ratio``), u the Darboux vector in the material frame,
t = T L^2 / B1 a dead tension pulling the far end along the axis (tension control); under
shortening control (``shortening`` e) the far end is held at height 1 - e instead. The
constraints g(x) = 0 are the far end's position, int d3_x ds = int d3_y ds = 0 (and
int d3_z ds = 1 - e), with multipliers mu (``jaxrod.solvers.constrained``): the reactions.
The end reactions reported:

    twist moment  m = M L / B1 = (1 / 2 pi) dE/d(turns)   (the moment about the axis that
                                                          the far clamp applies),
    tension       t = T L^2 / B1 = the input, or -mu_z under shortening control.

The isotropic rod (beta = 1) has a symmetry: turning the bent shape about the axis (the
fields v = (v1, v2) rotated at every s, psi unchanged) keeps the energy and both clamps, so
every bent equilibrium belongs to a circle of them and has a zero eigenvalue. The branch
pins it by a phase condition (``jaxrod.twisted.branch``): ``orbit_direction`` is its
generator, (-v2, v1, 0).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.framed import (
    FRAMED_SUPPORTS,
    FramedDiscretisation,
    frame,
    framed_discretisation,
)
from jaxrod.discretise.grid_map import check_layer_width
from jaxrod.params import ParameterError
from jaxrod.twisted.distributed import (
    POSITIONS_KEY,
    acts_on_positions,
    distributed_energy,
    quad_positions,
)
from jaxrod.twisted.self_contact import CONTACT_DEGREE_FACTOR, contact_energy, self_contact

#: Multipliers are solved for in units of the clamped-clamped Euler load 4 pi^2 B1 / L^2, so
#: that the continuation's inner product weighs them like the shape's values.
MULTIPLIER_UNIT = 4.0 * math.pi**2

#: The centring's stiffness (``TwistedRod.centred``): a slide by ds costs about
#: CENTRING_STIFFNESS (ds int |v|^2)^2 / 2, of the order of the bending energy's own
#: stiffness for a localised helix (int |v|^2 about 0.1).
CENTRING_STIFFNESS = 1.0e4

#: The self-contact penalty's default stiffness kappa (``jaxrod.twisted.self_contact``; in
#: B1 / L per L^2): PyElastica's rod (h = 0.007 L) looped at tensions near 2 x 10^4 is held
#: with its strands overlapping by about 1% of h (3% at 10^10).
CONTACT_STIFFNESS = 1.0e11

#: The key of the self-contact's data among a program's loads (no scene term's name).
CONTACT_KEY = "self contact"

#: The centring's stiffness on a rod with self-contact: a looped state's slide along the rod
#: moves its contact zone across the contact grid's nodes, and the penalty's quadrature
#: error there (eigenvalues of order 0.1 in the Hessian's units at n = 128) outweighs the
#: 1e4 of the rod without contact, giving the slide a spurious sign.
CONTACT_CENTRING_STIFFNESS = 1.0e8

#: C / B1 of a circular section of Poisson ratio 1/2 (C / B = 1 / (1 + nu)).
DEFAULT_TWIST_RATIO = 2.0 / 3.0


@dataclasses.dataclass(frozen=True)
class TwistedRod:
    """A rod clamped at both ends, the far end turned (module docstring).

    twist_ratio: gamma = C / B1 > 0 (default 2/3: a circular section with Poisson ratio 1/2;
      ``from_poisson_ratio``). bending_ratio: B2 / B1 > 0. Exactly one of ``tension`` (T L^2 /
      B1, a dead load along the axis; any sign) and ``shortening`` (the far end at
      (1 - shortening) L, 0 < shortening < 1). n: the Chebyshev degree of each of the three
      fields (>= 8). layer_width: None (the plain Chebyshev grid) or the width (in L) of a
      layer at the middle that the grid gathers its nodes into
      (``jaxrod.discretise.grid_map``): for states localised there, the localised helix of
      width about 1 / k (k = sqrt(4 t - m^2) / 2). centred: hold a localised state's
      centre at the middle (``centre_of_bending``), where its slide along the rod is a
      direction of nearly zero stiffness (exp(-k) of the others), below the arithmetic's
      resolution from k of about 25: the energy gains sigma H^2 / 2 (sigma =
      CENTRING_STIFFNESS, or CONTACT_CENTRING_STIFFNESS with self-contact), zero with
      its gradient on every state symmetric about the middle (the localised helix), so
      those stay the rod's equilibria and the slide is counted stable; a state it would
      move is reported not converged. contact_diameter: None (the strands may pass through
      each other) or the rod's diameter h in L (0 < h <= 0.1; both ends held): the strands
      repel where closer than h (``jaxrod.twisted.self_contact``), with the penalty's
      stiffness ``contact_stiffness``, on a grid of degree ``contact_grid`` n."""

    twist_ratio: float = DEFAULT_TWIST_RATIO
    bending_ratio: float = 1.0
    tension: float | None = None
    shortening: float | None = None
    n: int = 48
    loads: dict = dataclasses.field(default_factory=dict)
    support: str = "clamped-clamped"
    load_scale: float = 1.0
    layer_width: float | None = None
    centred: bool = False
    contact_diameter: float | None = None
    contact_stiffness: float = CONTACT_STIFFNESS
    contact_grid: int = CONTACT_DEGREE_FACTOR

    def __post_init__(self):
        check_layer_width(self.layer_width)
        h = self.contact_diameter
        if h is not None:
            if not (isinstance(h, (int, float)) and math.isfinite(h) and 0.0 < h <= 0.1):
                raise ParameterError(f"contact_diameter: a number in (0, 0.1] (rod lengths), "
                                     f"got {h!r}")
            if self.support != "clamped-clamped":
                raise ParameterError("contact_diameter: self-contact needs both ends held "
                                     "(support = \"clamped-clamped\")")
        k = self.contact_stiffness
        if not (isinstance(k, (int, float)) and math.isfinite(k) and k > 0):
            raise ParameterError(f"contact_stiffness: a finite number > 0, got {k!r}")
        if not (isinstance(self.contact_grid, (int, np.integer)) and 1 <= self.contact_grid
                <= 16):
            raise ParameterError(f"contact_grid: an integer in [1, 16] (the contact grid's "
                                 f"degree in units of n), got {self.contact_grid!r}")
        if not isinstance(self.centred, bool):
            raise ParameterError(f"centred: True or False, got {self.centred!r}")
        for name in ("twist_ratio", "bending_ratio"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ParameterError(f"{name}: a finite number > 0, got {value!r}")
        if self.support not in FRAMED_SUPPORTS:
            raise ParameterError(f"support: one of {', '.join(FRAMED_SUPPORTS)}, got "
                                 f"{self.support!r}")
        if not math.isfinite(self.load_scale):
            raise ParameterError(f"load_scale: a finite number, got {self.load_scale!r}")
        if self.support == "clamped":
            if self.tension is not None or self.shortening is not None:
                raise ParameterError("tension, shortening: a rod with a free end (support = "
                                     "\"clamped\") takes neither")
        elif (self.tension is None) == (self.shortening is None):
            raise ParameterError("tension, shortening: give exactly one (the far end pulled by "
                                 "a dead tension, or held at 1 - shortening)")
        if self.tension is not None and not math.isfinite(self.tension):
            raise ParameterError(f"tension: a finite number, got {self.tension!r}")
        if self.shortening is not None and not (0.0 < self.shortening < 1.0):
            raise ParameterError(f"shortening: in (0, 1), got {self.shortening!r}")
        if not isinstance(self.n, (int, np.integer)) or self.n < 8:
            raise ParameterError(f"n: an integer >= 8, got {self.n!r}")
        if not isinstance(self.loads, dict):
            raise ParameterError("loads: a dict of scene terms by name")
        if sum(bool(getattr(t, "elastic", False)) for t in self.loads.values()) > 1:
            raise ParameterError("loads: one taper (TaperedBending) at most")
        for name, t in self.loads.items():
            if not hasattr(t, "term_name") or (getattr(t, "elastic", False)
                                               and t.term_name != "tapered_bending"):
                raise ParameterError(f"loads: {name!r} is not a load term of "
                                     "jaxrod.scenes.terms (the rod's own energy is built in; "
                                     "a taper is a TaperedBending among the loads)")
            if t.distributed is not None and not acts_on_positions(t):
                raise ParameterError(f"loads: {name!r} ({t.term_name}) acts on the positions "
                                     "along the rod with no form for a rod that carries its "
                                     "frame (framed_distributed)")

    @property
    def symmetric(self) -> bool:
        """Whether turning a bent state about the axis keeps the energy: an isotropic section
        (B2 = B1) and every load unchanged by rotations about e3 (host side, concrete
        inputs). Then each bent equilibrium lies on a circle of them."""
        return self.bending_ratio == 1.0 and all(_axial(t) for t in self.loads.values())

    @classmethod
    def from_poisson_ratio(cls, poisson_ratio: float, **kwargs) -> TwistedRod:
        """A circular section: C / B = 1 / (1 + nu), -1 < nu <= 1/2."""
        if not (-1.0 < poisson_ratio <= 0.5):
            raise ParameterError(f"poisson_ratio: in (-1, 0.5], got {poisson_ratio!r}")
        return cls(twist_ratio=1.0 / (1.0 + poisson_ratio), **kwargs)

    @property
    def control(self) -> str:
        """"tension", "shortening" or "free" (support = "clamped")."""
        return "free" if self.support == "clamped" else \
            "tension" if self.tension is not None else "shortening"

    @property
    def constraints(self) -> int:
        """How many constraints hold the far end: 0 (free), 2 (on the axis) or 3 (and its
        height)."""
        return {"free": 0, "tension": 2, "shortening": 3}[self.control]

    @property
    def free_values(self) -> int:
        """The free nodal values of one field: n - 1 (both ends held) or n (a free end)."""
        return self.n if self.support == "clamped" else self.n - 1

    def discretisation(self, n: int | None = None) -> FramedDiscretisation:
        return framed_discretisation(self.n if n is None else n, self.support,
                                     layer_width=self.layer_width)

    def replace(self, key: str, value: float) -> TwistedRod:
        """A copy with the input ``key`` (``INPUTS`` or a load's "term.field[.i]") set."""
        if key in INPUTS:
            return dataclasses.replace(self, **{key: float(value)})
        name, field, index = _load_key(self, key)
        t = self.loads[name]
        if index is not None:
            array = np.asarray(getattr(t, field), float).copy()
            array[index] = value
            value = array
        else:
            value = float(value)
        loads = dict(self.loads)
        loads[name] = dataclasses.replace(t, **{field: value})
        return dataclasses.replace(self, loads=loads)

    def value(self, key: str) -> float:
        """The input ``key`` (``INPUTS`` or a load's "term.field[.i]") on this rod;
        ParameterError naming a key it does not have."""
        if key in INPUTS:
            value = getattr(self, key)
            if value is None:
                raise ParameterError(f"{key}: not an input of this rod (its far end is "
                                     f"under {self.control} control)")
            return float(value)
        name, field, index = _load_key(self, key)
        value = np.asarray(getattr(self.loads[name], field))
        return float(value if index is None else value[index])

    def program_loads(self) -> dict:
        """The loads as a program carries them: the rod's, the positions' data
        (``POSITIONS_KEY``) where a load acts on the positions along the rod, and the
        self-contact's (``CONTACT_KEY``) where it has a diameter."""
        loads = dict(self.loads)
        if any(acts_on_positions(t) for t in self.loads.values()):
            loads[POSITIONS_KEY] = quad_positions(self.discretisation(), self.layer_width)
        if self.contact_diameter is not None:
            loads[CONTACT_KEY] = self_contact(
                self.n, self.layer_width, self.contact_diameter, self.contact_stiffness,
                self.contact_grid * self.n)
        return loads

    def inputs(self) -> jax.Array:
        """(gamma, beta, t, e, load scale, centring stiffness): the traced inputs of the
        energy."""
        sigma = CENTRING_STIFFNESS if self.contact_diameter is None else \
            CONTACT_CENTRING_STIFFNESS
        return jnp.array([self.twist_ratio, self.bending_ratio, self.tension or 0.0,
                          self.shortening or 0.0, self.load_scale,
                          sigma if self.centred else 0.0])


#: The rod's own inputs, by name, in the order of ``TwistedRod.inputs``.
INPUTS = ("twist_ratio", "bending_ratio", "tension", "shortening", "load_scale")


def _axial(t) -> bool:
    """Whether the load term ``t`` is unchanged by rotations about e3 (concrete inputs)."""
    name = t.term_name
    if name == "tapered_bending":  # a section that changes along the rod, round at every s
        return True
    if name in ("gravity", "anisotropy"):
        d = np.asarray(t.direction, float)
        return bool(abs(d[0]) + abs(d[1]) == 0.0)
    if name == "zeeman":
        return bool(math.sin(float(t.angle)) == 0.0 or float(t.load) == 0.0)
    if name == "programmed":
        return bool(math.sin(float(t.angle)) == 0.0 and not np.any(np.asarray(t.profile)))
    return False


def _load_key(rod: TwistedRod, key: str) -> tuple[str, str, int | None]:
    """(term, field, index) of a load input "term.field[.i]"; ParameterError naming it."""
    parts = key.split(".")
    fields = [f.name for f in dataclasses.fields(rod.loads[parts[0]])] \
        if parts[0] in rod.loads else []
    ok = len(parts) in (2, 3) and parts[1] in fields
    if ok:
        shape = np.shape(getattr(rod.loads[parts[0]], parts[1]))
        ok = (len(parts) == 2 and shape == ()) or (
            len(parts) == 3 and parts[2].isdigit() and len(shape) == 1
            and int(parts[2]) < shape[0])
    if not ok:
        keys = ["turns", *INPUTS] + [f"{n}.{f.name}" for n, t in rod.loads.items()
                                     for f in dataclasses.fields(t)]
        raise ParameterError(f"vary: {key!r} is not an input of this rod; its inputs: "
                             f"{', '.join(keys)}")
    return parts[0], parts[1], int(parts[2]) if len(parts) == 3 else None


def framed_jet3(a):
    """(F, F', u) at one node from its jet (``jaxrod.discretise.framed.framed_jet``)."""
    F, dF = jax.jvp(lambda q: frame(q[0], q[1], q[2]), (a[:3],), (a[3:],))
    d1, d2, d3 = F[:, 0], F[:, 1], F[:, 2]
    return F, dF, jnp.stack([jnp.dot(dF[:, 1], d3), jnp.dot(dF[:, 2], d1),
                             jnp.dot(dF[:, 0], d2)])


def density(a, s, inputs, loads: dict) -> jax.Array:
    """The energy density at one node of jet a and arclength s: the rod's own
    f(s) (u1^2 + beta u2^2 + gamma u3^2) / 2 - t d3 . e3 (f = E I(s) / E I of a taper, a
    ``TaperedBending`` among the loads: the section's three stiffnesses scale alike, as a
    round section's I and J do; else 1), plus every load's density, written in
    the director (d3, d3') or, where the term has a ``framed`` form (a remanence at an angle
    in the material frame), in the frame."""
    gamma, beta, tension, scale = inputs[0], inputs[1], inputs[2], inputs[4]
    F, dF, u = framed_jet3(a)
    taper = [t.relative(s) for t in loads.values() if getattr(t, "elastic", False)]
    e = (0.5 * (taper[0] if taper else 1.0)
         * (u[0] ** 2 + beta * u[1] ** 2 + gamma * u[2] ** 2) - tension * F[2, 2])
    for t in loads.values():
        if getattr(t, "elastic", False):
            continue
        if getattr(t, "framed", None) is not None:
            e = e + scale * t.framed(F, dF, s)
        elif t.density is not None:
            e = e + scale * t.density(F[:, 2], dF[:, 2], s)
    return e


def endpoint(X, inputs, loads: dict) -> jax.Array:
    """The loads' potential of the far end's position X = int d3 (0 without one), times the
    load scale."""
    terms = [t for t in loads.values() if t.endpoint is not None]
    return inputs[4] * sum((t.endpoint(X) for t in terms), jnp.zeros((), X.dtype))


def tip(x, turns, disc: FramedDiscretisation) -> jax.Array:
    """X = int_0^1 d3 ds."""
    d3 = jax.vmap(lambda a: frame(a[0], a[1], a[2])[:, 2])(disc.jets(x, turns))
    return disc.integrate(d3.T)


def centre_of_bending(x, turns, disc: FramedDiscretisation) -> jax.Array:
    """H = int_0^1 (s - 1/2) (v1^2 + v2^2) ds, |v| the tangent's angle to the axis: zero on
    every state symmetric about the middle (turned end over end, |v(s)| = |v(1 - s)|); a
    slide by ds changes it by ds int |v|^2."""
    a = disc.jets(x, turns)
    return disc.integrate((disc.quad_nodes - 0.5) * (a[:, 0] ** 2 + a[:, 1] ** 2))


def energy(x, turns, disc: FramedDiscretisation, inputs, loads: dict | None = None) -> jax.Array:
    """E(x; turns) (module docstring) with the loads' terms (those that act on the
    positions along the rod: ``jaxrod.twisted.distributed``), the centring's
    inputs[5] H^2 / 2 (``TwistedRod.centred``) and the self-contact's penalty."""
    loads = {} if loads is None else loads
    e = disc.integrate(jax.vmap(density, in_axes=(0, 0, None, None))(
        disc.jets(x, turns), disc.quad_nodes, inputs, loads))
    e = (e + endpoint(tip(x, turns, disc), inputs, loads)
         + distributed_energy(x, turns, disc, inputs, loads)
         + 0.5 * inputs[5] * centre_of_bending(x, turns, disc) ** 2)
    contact = loads.get(CONTACT_KEY)
    return e if contact is None else e + contact_energy(x, contact)


def far_end(x, disc: FramedDiscretisation, inputs, count: int) -> jax.Array:
    """g(x): the far end's offset from the axis (and from height 1 - e: ``count`` = 3)."""
    d3 = jax.vmap(lambda a: frame(a[0], a[1], a[2])[:, 2])(disc.jets(x))
    g = jnp.stack([disc.integrate(d3[:, 0]), disc.integrate(d3[:, 1]),
                   disc.integrate(d3[:, 2]) - (1.0 - inputs[3])])
    return g[:count]


def orbit_direction(x, disc: FramedDiscretisation) -> jax.Array:
    """The symmetry's generator at x: (-v2, v1, 0) (module docstring)."""
    f = disc.free
    return jnp.concatenate([-x[f:2 * f], x[:f], jnp.zeros(f, x.dtype)])


def centreline(disc: FramedDiscretisation, x) -> np.ndarray:
    """(n + 1, 3): r(s) = int_0^s d3 at the Chebyshev nodes of the fields' grid."""
    field = disc.field
    values = np.asarray(field.to_full) @ np.asarray(x).reshape(3, disc.free).T
    d3 = np.asarray(jax.vmap(lambda v: frame(v[0], v[1], v[2])[:, 2])(jnp.asarray(values)))
    return np.asarray(field.cumint) @ d3
