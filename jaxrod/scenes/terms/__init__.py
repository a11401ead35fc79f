"""Energy terms: each one file, each registered by name, composed into a ``Scene``.

A term is a small frozen dataclass of inputs (every field is traced, so changing an input
never recompiles) that contributes to the nondimensional energy through one or more of

    density(d3, dd3, s)   an energy density of the local jet: the director d3(s) and its
                          derivative d3'(s) (3-vectors) at the arclength s in [0, 1];
    endpoint(X)           a potential of the tip position X = int_0^1 d3 ds (3-vector), where
                          a distributed term is an exact derivative along the rod (a field
                          acting on a magnetisation along the tangent);
    distributed(r, d3, s, w)  a functional of the positions r(s_j) = int_0^{s_j} d3 and
                          directors at the quadrature nodes s_j with weights w_j (a
                          non-uniform field acting on a magnetisation that is not along the
                          tangent): differentiated by autodiff as a whole.

Terms are written in the director, so one term serves the planar rod (d3 = sin(theta) e1 +
cos(theta) e3) and the 3D rod alike. A density term may add ``planar(theta, theta', s)``, the
same density on the planar rod written in theta (the compiled derivative programs are then
smaller: no sin^2 + cos^2 to carry through three derivatives), and an endpoint term
``planar_endpoint(X)`` of the in-plane tip (X1, X3); tests/test_engine.py checks that the
forms agree. ``elastic = True`` marks the rod's own energy (the
bending term), which the load ramp of ``jaxrod.equilibria`` does not scale.

A new term is one file with a class decorated by ``@term("name")`` (this registers it in
``TERMS``, by which scene files name it) and nothing else: the derivatives, solvers and
analyses take it as they take the paper's terms.
"""

from __future__ import annotations

import dataclasses

import jax

#: Every registered term by its name: those imported so far (a shipped term is imported on
#: first use; ``jaxrod.scenes.files``, which reads scene files, imports them all).
TERMS: dict[str, type] = {}


def term(name: str):
    """Class decorator: a frozen dataclass of traced inputs, registered as ``TERMS[name]``.

    The class defines ``density``, ``endpoint`` and/or ``distributed`` (module docstring);
    the ones it does not define stay ``None``."""
    def register(cls):
        for kind in ("density", "endpoint", "distributed", "planar", "planar_endpoint"):
            if not hasattr(cls, kind):
                setattr(cls, kind, None)
        if not hasattr(cls, "elastic"):
            cls.elastic = False
        cls = jax.tree_util.register_dataclass(dataclasses.dataclass(frozen=True)(cls))
        if name in TERMS and TERMS[name].__qualname__ != cls.__qualname__:
            raise ValueError(f"a term named {name!r} is already registered ({TERMS[name]})")
        TERMS[name] = cls
        cls.term_name = name
        return cls
    return register


#: The shipped terms: class name -> its module, imported on first use (a scene of the paper's
#: terms does not import the others; ``jaxrod.scenes.files`` imports them all).
SHIPPED = {"Anisotropy": "anisotropy", "Bending": "bending", "Dipole": "dipole",
           "Gravity": "gravity", "PathDipole": "path_dipole", "PointDipole": "point_dipole",
           "ProgrammedDipole": "programmed_dipole",
           "ProgrammedMagnetisation": "programmed", "TaperedBending": "tapered_bending",
           "Zeeman": "zeeman"}


def __getattr__(name: str):
    if name in SHIPPED:
        import importlib

        return getattr(importlib.import_module(f"jaxrod.scenes.terms.{SHIPPED[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["TERMS", "term", "Anisotropy", "Bending", "Dipole", "Gravity", "PathDipole",
           "PointDipole", "ProgrammedDipole", "ProgrammedMagnetisation", "TaperedBending",
           "Zeeman"]
