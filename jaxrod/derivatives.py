"""Exact derivatives of the discrete energies, assembled from their structure.

Every scene's discrete energy has the form (planar or 3D, uniform field or magnet)

    E(x) = sum_j w_j rho(a_j, s_j)  +  Psi(X),      X = sum_j w_j chi(a_j),      a_j = L_j x,

where x are the unknowns, a_j the *jet* at quadrature node s_j (the field and its
derivative there: (theta, theta') in the plane, (v1, v2, v1', v2') for the director chart),
L_j the (r x m) interpolation rows of the discretisation (``jet_matrix``), w_j the
Clenshaw-Curtis weights, rho the pointwise energy density (bending, gravity, anisotropy),
chi the pointwise integrand of the tip position (the director) and Psi the endpoint
potential of the magnet (absent in a uniform field). Differentiating the structure instead
of the whole energy,

    grad E    = sum_j L_j^T l_j'(a_j),                      l_j(a) = w_j [rho(a, s_j) + g . chi(a)]
    Hess E    = sum_j L_j^T l_j''(a_j) L_j + B^T Psi''(X) B,  B = sum_j w_j chi'(a_j) L_j,
    D^3E[phi] = d/de Hess E(x + e phi)|_0                   (forward mode through the above)

with g = grad Psi(X): only the r-variable densities and the k-variable potential (r <= 4,
k <= 3) are differentiated by autodiff; the rest is small matrix products. Everything stays
exact (autodiff, no finite differences), and the compiled programs are a fraction of the size
of jacfwd through the whole energy (third derivatives appear in every Moore-Spence step).

``EnergyModel`` is what the solvers take: energy, gradient, Hessian, third-derivative
contraction and the derivatives in the continuation parameter lam, each a pure function of
(x, lam, args). ``Structured(scene_at)`` assembles them from a scene's ``density``,
``tip_map`` and ``endpoint`` (``scene_at(lam, args) -> (scene, disc)`` puts lam into the
scene); ``Autodiff(energy)`` differentiates any energy function as a whole (for the reduced
energies and other one-off functions). Both are hashable and compare equal when built from
the same functions, so compiled programs are reused.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp


class FoldJet(NamedTuple):
    """The blocks of the Moore-Spence Jacobian at (x, lam) and null-vector estimate phi:
    F = grad E, H = Hess E, F_lam = d/dlam grad E, third = D^3E[phi], Hphi_lam = (H phi)_lam,
    and with a second parameter u, F_u and Hphi_u (``EnergyModel.fold_blocks``)."""

    F: jax.Array
    H: jax.Array
    F_lam: jax.Array
    third: jax.Array
    Hphi_lam: jax.Array
    F_u: jax.Array | None = None
    Hphi_u: jax.Array | None = None


class EnergyModel:
    """Energy E(x, lam, args) and its exact derivatives (the interface the solvers use).

    Subclasses define ``energy``, ``gradient`` and ``hessian``; the rest follows by forward
    mode of those (cheap when they are assembled).
    """

    def energy(self, x, lam, args):
        raise NotImplementedError

    def gradient(self, x, lam, args):
        raise NotImplementedError

    def hessian(self, x, lam, args):
        raise NotImplementedError

    def gradient_and_hessian(self, x, lam, args):
        """(grad E, Hess E) at (x, lam) (one assembly where the two share their parts)."""
        return self.gradient(x, lam, args), self.hessian(x, lam, args)

    def third(self, x, lam, args, phi):
        """D^3E(x)[phi] = d/de Hess E(x + e phi) at e = 0 (an m x m matrix)."""
        return jax.jvp(lambda z: self.hessian(z, lam, args), (x,), (phi,))[1]

    def gradient_lam(self, x, lam, args):
        """d/dlam grad E (the parameter column of the equilibrium Jacobian)."""
        lam = jnp.asarray(lam, x.dtype)
        return jax.jvp(lambda l: self.gradient(x, l, args), (lam,), (jnp.ones_like(lam),))[1]

    def linearisation(self, x, lam, args):
        """(grad E, Hess E, d/dlam grad E) at (x, lam): the equilibrium residual and the
        blocks of its Jacobian in (x, lam), from one assembly and one tangent in lam."""
        lam = jnp.asarray(lam, x.dtype)
        (F, H), (F_lam, _) = jax.jvp(lambda l: self.gradient_and_hessian(x, l, args), (lam,),
                                     (jnp.ones_like(lam),))
        return F, H, F_lam

    def hessian_and_gradient_lam(self, x, lam, args):
        """(Hess E, d/dlam grad E) at (x, lam): the bordered Jacobian's blocks."""
        _, H, F_lam = self.linearisation(x, lam, args)
        return H, F_lam

    def fold_blocks(self, x, lam, args, phi, second=None) -> FoldJet:
        """The Moore-Spence residual's gradient block and its Jacobian's blocks at (x, lam)
        with null-vector estimate phi (``FoldJet``), from one assembly of (grad E, Hess E)
        and its forward tangents along (phi, 0) and (0, 1) in (x, lam). With ``second =
        (args_at, u)``, a second parameter u entering the energy as ``args_at(u, args)``,
        a third tangent (0, 0, 1) in (x, lam, u) adds the u column (F_u, (H phi)_u) of the
        fold-curve system. The one assembly of the fold Jacobian: ``jaxrod.solvers.folds``
        lays it out, the fold curves and the reduced jet read it."""
        lam = jnp.asarray(lam, x.dtype)
        zero = jnp.zeros_like(phi)
        if second is None:
            pair = lambda z, l: self.gradient_and_hessian(z, l, args)
            primals, tangents = (x, lam), (jnp.stack([phi, zero]), jnp.array([0.0, 1.0], x.dtype))
        else:
            args_at, u = second
            pair = lambda z, l, v: self.gradient_and_hessian(z, l, args_at(v, args))
            eye = jnp.eye(3, dtype=x.dtype)
            primals = (x, lam, jnp.asarray(u, x.dtype))
            tangents = (jnp.stack([phi, zero, zero]), eye[1], eye[2])
        (F, H), (dg, dH) = jax.vmap(lambda *t: jax.jvp(pair, primals, t),
                                    out_axes=(None, 0))(*tangents)
        if second is None:
            return FoldJet(F, H, dg[1], dH[0], dH[1] @ phi)
        return FoldJet(F, H, dg[1], dH[0], dH[1] @ phi, dg[2], dH[2] @ phi)


@dataclasses.dataclass(frozen=True)
class Autodiff(EnergyModel):
    """Derivatives of ``energy(x, lam, args)`` by autodiff of the whole function."""

    fn: Callable[[jax.Array, Any, Any], jax.Array]

    def energy(self, x, lam, args):
        return self.fn(x, lam, args)

    def gradient(self, x, lam, args):
        return jax.grad(self.fn)(x, lam, args)

    def hessian(self, x, lam, args):
        return jax.jacfwd(jax.grad(self.fn))(x, lam, args)


def as_model(energy) -> EnergyModel:
    """An ``EnergyModel`` as it is, or a plain energy function wrapped in ``Autodiff``."""
    return energy if isinstance(energy, EnergyModel) else Autodiff(energy)


def _jets(L, x):
    """a_j = L_j x for every quadrature node: (nq, r)."""
    return jnp.einsum("jrm,m->jr", L, x)


def _sandwich(L, local, L2=None):
    """sum_j L_j^T local_j L2_j for L (nq, r, m), local (nq, r, r)."""
    L2 = L if L2 is None else L2
    nq, r, m = L.shape
    right = jnp.einsum("jrs,jsn->jrn", local, L2).reshape(nq * r, -1)
    return L.reshape(nq * r, m).T @ right


@dataclasses.dataclass(frozen=True)
class Structured(EnergyModel):
    """Derivatives assembled from a scene's structure (module docstring).

    ``scene_at(lam, args) -> (scene, disc)``. The scene provides ``density(a, s)`` (scalar
    energy density of the jet a at node s), and for an endpoint term ``tip_map(a)`` (the
    k-vector integrand of X) and ``endpoint(X)`` (scalar); ``tip_map = None`` means no
    endpoint term. A scene with ``has_distributed`` adds ``distributed_energy(x, disc)``
    (terms of the positions along the rod), differentiated by autodiff as a whole. The
    discretisation provides ``jet_matrix`` (nq, r, m), ``quad_weights``
    and ``quad_nodes``.
    """

    scene_at: Callable[[Any, Any], tuple[Any, Any]]

    def _setup(self, x, lam, args):
        scene, disc = self.scene_at(lam, args)
        L = disc.jet_matrix
        return scene, L, _jets(L, x), disc.quad_weights, disc.quad_nodes

    @staticmethod
    def _tip(scene, a, w):
        return jnp.einsum("j,jk->k", w, jax.vmap(scene.tip_map)(a))

    def energy(self, x, lam, args):
        scene, _, a, w, s = self._setup(x, lam, args)
        e = jnp.dot(w, jax.vmap(scene.density)(a, s))
        if scene.tip_map is not None:
            e = e + scene.endpoint(self._tip(scene, a, w))
        return e + self._distributed(x, lam, args)

    def _distributed(self, x, lam, args):
        """The scene's distributed terms (positions along the rod), 0 without them."""
        scene, disc = self.scene_at(lam, args)
        if not getattr(scene, "has_distributed", False):
            return jnp.zeros((), x.dtype)
        return scene.distributed_energy(x, disc)

    def _local(self, scene, a, w):
        """l_j(a) = w_j [rho(a, s_j) + g . chi(a)] with g = grad Psi(X) held fixed, X, and
        Psi''(X) (None, None, None without an endpoint term)."""
        if scene.tip_map is None:
            return (lambda aj, sj, wj: wj * scene.density(aj, sj)), None, None
        X = self._tip(scene, a, w)
        P, g = _hessian_and_gradient(scene.endpoint)(X)
        return (lambda aj, sj, wj: wj * (scene.density(aj, sj)
                                         + jnp.dot(g, scene.tip_map(aj)))), X, P

    def gradient(self, x, lam, args):
        scene, L, a, w, s = self._setup(x, lam, args)
        local, _, _ = self._local(scene, a, w)
        F = jnp.einsum("jrm,jr->m", L, jax.vmap(jax.grad(local))(a, s, w))
        if getattr(scene, "has_distributed", False):
            F = F + jax.grad(self._distributed)(x, lam, args)
        return F

    def hessian(self, x, lam, args):
        return self.gradient_and_hessian(x, lam, args)[1]

    def gradient_and_hessian(self, x, lam, args):
        scene, L, a, w, s = self._setup(x, lam, args)
        local, X, P = self._local(scene, a, w)
        h, g = jax.vmap(_hessian_and_gradient(local))(a, s, w)  # (nq, r, r), (nq, r)
        F = jnp.einsum("jrm,jr->m", L, g)
        H = _sandwich(L, h)
        if X is not None:
            chi_a = jax.vmap(jax.jacfwd(scene.tip_map))(a)  # (nq, k, r)
            B = jnp.einsum("j,jkr,jrm->km", w, chi_a, L)
            H = H + B.T @ P @ B
        if getattr(scene, "has_distributed", False):
            F = F + jax.grad(self._distributed)(x, lam, args)
            H = H + jax.hessian(self._distributed)(x, lam, args)
        return F, H


def _hessian_and_gradient(f):
    """a -> (Hess f(a), grad f(a)) by forward over reverse mode, one pass (first argument)."""
    def both(a, *rest):
        v = jax.grad(f)(a, *rest)
        return v, v
    return jax.jacfwd(both, has_aux=True)
