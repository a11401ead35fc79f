"""``jaxrod equilibrium RIG`` and ``jaxrod branch RIG --vary KEY`` for a rod that carries its
frame (``jaxrod.twisted``): held at both ends (support = "clamped-clamped"), or a 3D
cantilever programmed at an angle. The far end's twisting moment ``twist_moment``
(M L / B) and ``tension`` (T L^2 / B, the clamp's pull), the twist and writhe, the tip's
angles and position, the count of unstable directions; along a branch its folds and
``branch_points`` (their ``value`` in the varied key's unit: turns for
``ends.rotation_turns``)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from jaxrod.cli._inputs import _float
from jaxrod.params import ParameterError
from jaxrod.status import Status

#: The path's degree where --n is not given: a localised helix of tens of turns needs it
#: (at 16 the path to PyElastica's case ends on another, unstable, state).
PATH_DEGREE = 48
#: The most the degree is raised to (doubling) until the state's Chebyshev tail is <= 1e-8.
MOST_DEGREE = 256


def add_grid_options(p, branch: bool = False) -> None:
    """--layer-width and --centred: the grid and the centring of a rod that carries its
    frame (``jaxrod.twisted.TwistedRod``); for a branch also --max-folds."""
    p.add_argument("--layer-width", type=_float("layer-width"), default=None,
                   metavar="W", help="a rod that carries its frame: gather the grid into a "
                   "layer of width W (in L, 0 < W <= 1) at the middle, for a state localised "
                   "there (a localised helix: W about 2 / sqrt(4 t - m^2))")
    p.add_argument("--centred", action="store_true",
                   help="a rod that carries its frame: hold a localised state's centre at the "
                   "middle (its slide along the rod, nearly free, counted stable)")
    if branch:
        p.add_argument("--max-folds", type=_count, default=None, metavar="K",
                       help="a rod that carries its frame: end the branch at its K-th fold "
                       "(K >= 1)")


def _count(text: str) -> int:
    """The --max-folds parser: an integer >= 1."""
    import argparse

    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"max-folds must be an integer >= 1, got {text!r}")
    return value


def check_grid_options(args, file) -> None:
    """ParameterError where the grid options come with a rod that carries no frame."""
    for name, given in (("layer-width", getattr(args, "layer_width", None) is not None),
                        ("centred", getattr(args, "centred", False)),
                        ("max-folds", getattr(args, "max_folds", None) is not None)):
        if given and file.framed is None:
            raise ParameterError(f"{name}: only for a rod that carries its frame (support = "
                                 "\"clamped-clamped\", or a 3D cantilever programmed at an "
                                 "angle)")


def twisted_rod(file, n: int, args=None):
    """The ``TwistedRod`` of a file's framed rod, at degree n, on the grid and with the
    centring that ``args`` ask for."""
    from jaxrod.twisted.rod import DEFAULT_TWIST_RATIO, TwistedRod

    h = file.framed
    return TwistedRod(DEFAULT_TWIST_RATIO if h.twist_ratio is None else h.twist_ratio,
                      h.bending_ratio, h.tension, h.shortening, n, h.loads, h.support,
                      layer_width=getattr(args, "layer_width", None),
                      centred=bool(getattr(args, "centred", False)),
                      contact_diameter=h.contact_diameter)


def _resolved(rod, turns: float):
    """The rod's equilibrium at ``turns`` (``twisted_equilibrium``) at its degree, then at
    twice the degree from it, and so on, until resolved."""
    from jaxrod.twisted.branch import twisted_equilibrium

    state = twisted_equilibrium(rod, turns)
    path_tail, n = state.path_tail, rod.n
    while state.converged and state.status == Status.UNDER_RESOLVED and n < MOST_DEGREE:
        n = min(2 * n, MOST_DEGREE)
        state = twisted_equilibrium(dataclasses.replace(rod, n=n), turns, start=state)
    return dataclasses.replace(state, path_tail=path_tail)


def _degree(args) -> int:
    return PATH_DEGREE if getattr(args, "n_default", True) else args.n


def framed_range(args, file) -> tuple[str, float, float, float]:
    """(the rod's input, start, stop, its factor) of ``--vary KEY --from A --to B``
    (start and stop in the file's units)."""
    if getattr(args, "stop", None) is None and getattr(args, "to", None) is not None:
        args.stop = args.to
    if args.vary is None or args.start is None or args.stop is None:
        raise ParameterError("vary: give --vary KEY --from A --to B with a scene file")
    key, factor = file.input_of(args.vary)
    if args.start == args.stop:
        raise ParameterError(f"to: must differ from --from ({args.start:g})")
    return key, args.start, args.stop, factor


def _fields(state, file) -> dict:
    """A state's report, the file's length unit for the far end's position."""
    X, tangent = state.tip_position(), state.tip_tangent()
    out = state.as_dict()
    out.update(tip_angle_deg=float(np.degrees(np.arctan2(X[0], X[2]))),
               tip_tangent_deg=float(np.degrees(np.arctan2(tangent[0], tangent[2]))),
               tip_position=[float(v) * file.length for v in X],
               stable=state.unstable == 0, residual_norm=state.residual,
               error_estimate=state.tail, path_error_estimate=state.path_tail,
               message=state.status.message)
    return out


def _path_warning(state) -> str:
    """A line where the path that reached the state was under-resolved, else empty."""
    from jaxrod.equilibria.resolution import TOLERANCE

    if not state.path_tail > TOLERANCE:
        return ""
    return (f"\n  the path to it was under-resolved (Chebyshev tail up to {state.path_tail:.1e} "
            "on its grid): it may have reached another equilibrium than a resolved path "
            "would; raise --n or give --layer-width")


def framed_equilibrium(args, file) -> int:
    state = _resolved(twisted_rod(file, _degree(args), args), file.framed.turns)
    out = {"rig": args.rig, "set": args.set, **_fields(state, file)}
    if args.json:
        print(json.dumps(out))
    elif file.framed.support == "clamped":
        print(f"{args.rig}: tip angle {out['tip_angle_deg']:.10f} deg, tip tangent "
              f"{out['tip_tangent_deg']:.10f} deg, tip at "
              f"({', '.join(f'{v:.6g}' for v in out['tip_position'])}); "
              f"{'stable' if state.unstable == 0 else f'{state.unstable} unstable'}; "
              f"{out['message']} (n = {state.rod.n}, Chebyshev tail {state.tail:.1e})"
              + _path_warning(state))
    else:
        print(f"{args.rig}: {state.turns:.10g} turns, twisting moment M L/B = "
              f"{state.twist_moment:.10g}, tension T L^2/B = {state.tension:.10g}; Tw "
              f"{state.twist:.6g}, Wr {state.writhe:.6g}; "
              f"{'stable' if state.unstable == 0 else f'{state.unstable} unstable'}; "
              f"{out['message']} (n = {state.rod.n}, Chebyshev tail {state.tail:.1e})"
              + _path_warning(state))
    return 0 if state.status == Status.SUCCESS else 1


def framed_branch(args, file, start: float, stop: float) -> int:
    """The branch along ``args.vary`` from ``start`` to ``stop`` (the file's units), from the
    file's equilibrium at ``start``."""
    from jaxrod.equilibria.resolution import TOLERANCE
    from jaxrod.twisted.branch import twist_branch, twisted_equilibrium

    key, factor = file.input_of(args.vary)
    rod = twisted_rod(file, _degree(args), args)
    if key == "turns":
        first = _resolved(rod, start)
    else:
        first = _resolved(rod.replace(key, start * factor), file.framed.turns)
    rod = first.rod
    folds = {} if getattr(args, "max_folds", None) is None else {"max_folds": args.max_folds}
    branch = twist_branch(rod, stop * factor, vary=key, start=first, **folds)
    tails = branch.column("tail")
    # a branch resolved at its start but not along the way: again at twice the degree (not
    # with self-contact: a contact state's kink makes its tail fall algebraically in n)
    while (np.max(tails) > TOLERANCE and rod.n < MOST_DEGREE and first.converged
           and rod.contact_diameter is None):
        rod = dataclasses.replace(rod, n=min(2 * rod.n, MOST_DEGREE))
        first = twisted_equilibrium(rod, first.turns, start=first)
        branch = twist_branch(rod, stop * factor, vary=key, start=first, **folds)
        tails = branch.column("tail")
    values = branch.column("value") / factor
    # the refined folds and branch points count in the resolution too
    tails = np.append(tails, [p.state.tail for p in branch.fold_points + branch.branch_points])
    ok = all(p.converged for p in branch.points) and all(
        p.converged for p in branch.branch_points + branch.fold_points)
    # the end of the range, or the folds asked for (--max-folds)
    complete = branch.complete or (bool(folds) and branch.status == int(Status.FOLDS_FOUND))
    status = (Status(branch.status) if not complete and branch.status in
              {s.value for s in Status} else Status.NOT_CONVERGED if not ok or not
              complete else Status.UNDER_RESOLVED if np.max(tails) > TOLERANCE
              else Status.SUCCESS)

    def point(state):
        return {"value": state.value / factor, **_fields(state, file)}

    out = {"vary": args.vary, "points": len(values), "value": values.tolist(),
           "twist_moment": branch.column("twist_moment").tolist(),
           "tension": branch.column("tension").tolist(),
           "unstable": branch.column("unstable").tolist(),
           **({"self_distance": branch.column("self_distance").tolist()}
              if rod.contact_diameter is not None else {}),
           "stable": [bool(u == 0) for u in branch.column("unstable")],
           "folds": [{**point(f.state), "converged": f.converged}
                     for f in branch.fold_points],
           "branch_points": [{**point(p.state), "unstable": list(p.unstable),
                              "kernel_dimension": abs(p.unstable[1] - p.unstable[0]),
                              "converged": p.converged} for p in branch.branch_points],
           "converged": status == Status.SUCCESS, "status": status.name.lower(),
           "message": branch.message if not complete else status.message,
           "complete": complete, "last_value": float(values[-1]), "n": rod.n,
           "error_estimate": float(np.max(tails))}
    if getattr(args, "out", None):
        from jaxrod.cli._output import _output_dir

        out_dir = _output_dir(args.out)
        (out_dir / "branch.json").write_text(json.dumps(out, indent=1))
        rows = np.column_stack([values, out["twist_moment"], out["tension"],
                                out["unstable"]])
        np.savetxt(out_dir / "branch.csv", rows, delimiter=",", comments="",
                   header=f"{args.vary},twist_moment,tension,unstable")
        from jaxrod.cli.scene_file import branch_figure

        branch_figure(out_dir / "branch.png", values, np.array(out["twist_moment"]),
                      np.array(out["stable"]), out, args.vary, "twist_moment",
                      "twisting moment M L / B")
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{args.rig}: {len(values)} points along {args.vary} from {start:g} to "
              f"{stop:g}; {len(out['folds'])} folds, {len(out['branch_points'])} branch "
              f"points (n = {rod.n})")
        from jaxrod.cli.scene_file import print_points

        print_points(out, args.vary, lambda f: f"twisting moment {f['twist_moment']:.10g}, "
                                               f"tension {f['tension']:.10g}")
    return 0 if out["converged"] else 1
