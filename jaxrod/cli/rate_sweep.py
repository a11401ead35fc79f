"""``jaxrod sweep ... --rate R``: the magnet (or any scene file's input) moved at a finite
speed; the rod follows dynamically and switches later than the static fold, by the lag the
fold's normal form predicts (``jaxrod.dynamics.normal_form``), printed beside it."""

from __future__ import annotations

import json
import math
import sys

from jaxrod.cli._inputs import _float
from jaxrod.cli.scene_file import add_scene_file_inputs
from jaxrod.params import ParameterError


def rate_sweep_command(args) -> int:
    """``jaxrod sweep --G --M --D --rate R --damping C --from A --to B``: the magnet moved
    from A to B degrees at R degrees per unit time, from rest on the state a quasi-static
    sweep in the same direction holds at A (engaged moving away from the vertical,
    disengaged moving towards it)."""
    import numpy as np

    import jaxrod as jr
    from jaxrod.dynamics.rate_sweep import rate_sweep

    a, b = args.start_deg, args.stop_deg
    if a is None or b is None or a == b or not all(-90 <= v <= 90 for v in (a, b)):
        raise ParameterError("from/to: give --from A --to B, different magnet angles in "
                             "[-90, 90] degrees")
    if args.G is None or args.M is None or args.D is None:
        raise ParameterError("G: a sweep at a finite rate takes --G --M --D")
    if not (math.isfinite(args.rate) and args.rate > 0):
        raise ParameterError(f"rate must be a finite number > 0 (deg per unit time), got "
                             f"{args.rate!r}")
    _check_sweep_time(a, b, args.rate)
    if not (math.isfinite(args.damping) and args.damping >= 0):
        raise ParameterError(f"damping must be a finite number >= 0, got {args.damping!r}")
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(args.G),
                      "magnet": jr.Dipole(args.M, args.D, 0.0)})
    n = args.n or 16
    origin = 0.0 if abs(b) > abs(a) else math.copysign(90.0, a if a else b)
    path = np.radians(np.linspace(origin, a, max(2, int(abs(a - origin) / 0.25) + 1)))
    held = jr.sweep(scene, "magnet.alpha", path.tolist(), n=n)
    at = scene.replace("magnet.alpha", math.radians(a))
    s = rate_sweep(at, "magnet.alpha", held.states[-1], math.radians(b),
                   math.radians(args.rate), args.damping, dt=args.dt, n=n, tol=_tol(args))
    predicted = prediction(at, "magnet.alpha", held.states[-1], math.radians(b),
                           math.radians(args.rate), args.damping, n, math.radians(1.0))
    out = {"G": args.G, "M": args.M, "D": args.D, "rate_deg": args.rate,
           "damping": args.damping, "from_deg": a, "to_deg": b,
           "switch_alpha_deg": [math.degrees(v) for v in s.switches],
           "fold_alpha_deg": predicted and predicted["fold"],
           "predicted_switch_alpha_deg": predicted and predicted["switch"],
           "normal_form": predicted,
           "alpha_deg": np.degrees(s.values).tolist(), "time": s.trajectory.time.tolist(),
           "tip_angle_deg": s.trajectory.tip_angle_deg.tolist(),
           "converged": s.trajectory.converged}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"magnet from {a:g} to {b:g} deg at {args.rate:g} deg per unit time, drag "
              f"{args.damping:g}: switched at " + (", ".join(
                  f"{v:.6f}" for v in out["switch_alpha_deg"]) or "no angle") + " deg")
        print(_describe(predicted, "deg"))
    return 0 if s.trajectory.converged else 1


def sweep_on_file(args) -> int:
    """``jaxrod sweep RIG --vary KEY --from A --to B [--step S | --rate R --damping C]``:
    the input moved from A to B (the file's units) from the equilibrium reached by ramping
    the loads at A: quasi-statically in steps (snaps by energy descent), or at a finite
    rate (the motion); the values where the rod snapped, in order."""
    import numpy as np

    import jaxrod as jr
    from jaxrod.dynamics.rate_sweep import rate_sweep
    from jaxrod.scenes.files import load

    if args.vary is None or args.start_deg is None or args.stop_deg is None:
        raise ParameterError("vary: give --vary KEY --from A --to B with a scene file")
    file = load(args.rig, args.set)
    a, b = args.start_deg, args.stop_deg
    if a == b:
        raise ParameterError(f"to: must differ from --from ({a:g})")
    if args.rate is not None:
        if not (math.isfinite(args.rate) and args.rate > 0):
            raise ParameterError(f"rate must be a finite number > 0, got {args.rate!r}")
        _check_sweep_time(a, b, args.rate)
    out_dir = None
    if args.out is not None:
        from jaxrod.cli._output import _output_dir

        out_dir = _output_dir(args.out)
    from jaxrod.scenes.path import along

    at = along(file, (args.vary,)).at_host(a)
    start = jr.equilibrium(at, n=args.n or 16, throw=False)
    if args.rate is None:
        from jaxrod.progress import Interrupted

        step = args.step or abs(b - a) / 200.0
        values = np.linspace(a, b, max(2, int(round(abs(b - a) / step)) + 1))
        try:
            s = jr.sweep(file, args.vary, values.tolist(), n=args.n or 16,
                               state=start.state, progress=not args.quiet)
        except Interrupted as stop:
            if out_dir is not None:
                write_scene_sweep(out_dir, stop.partial, 1.0, args)
            print(f"jaxrod sweep: {stop.partial.reason}" + (
                f"; wrote what was computed to {out_dir / 'sweep.csv'} (marked incomplete)"
                if out_dir is not None else ""), file=sys.stderr)
            return 130
        switches = [snap["value"] for snap in s.snaps]
        converged = s.converged
        if out_dir is not None:
            write_scene_sweep(out_dir, s, 1.0, args)
    else:  # the motion: an input of the scene, moved at its rate
        key, factor = file.input_of(args.vary)
        at = file.scene.replace(key, factor * a)
        s = rate_sweep(at, key, start.state, factor * b, factor * args.rate, args.damping,
                       dt=args.dt, n=args.n or 16, tol=_tol(args))
        switches = [v / factor for v in s.switches]
        converged = s.trajectory.converged
        predicted = prediction(at, key, start.state, factor * b, factor * args.rate,
                               args.damping, args.n or 16, factor)
    out = {"rig": args.rig, "vary": args.vary, "from": a, "to": b, "rate": args.rate,
           "switches": switches, "converged": converged}
    if args.rate is not None:
        out["normal_form"] = predicted
    print(json.dumps(out) if args.json else
          f"{args.rig}: {args.vary} from {a:g} to {b:g}"
          + (f" at {args.rate:g} per unit time" if args.rate else " (quasi-static)")
          + ": snapped at " + (", ".join(f"{v:.8g}" for v in switches) or "no value")
          + ("\n" + _describe(predicted, "") if args.rate is not None else ""))
    return 0 if converged else 1


#: The shortest sweep, in time units L^2 sqrt(rho A_c / (E I)): the clamped rod's slowest
#: vibration period is 2 pi / 3.516 = 1.8, so a sweep a thousand times shorter is a jump
#: (the rod cannot follow; its response is the snap's: ``jaxrod snap``).
SHORTEST_SWEEP = 1e-3


def _check_sweep_time(a, b, rate) -> None:
    """A rate that moves the input over its range faster than the rod can respond is
    refused before any work (the sweep would be a jump, its lag meaningless)."""
    if abs(b - a) / rate < SHORTEST_SWEEP:
        raise ParameterError(f"rate: {rate:g} per unit time crosses the range in "
                             f"{abs(b - a) / rate:.3g} time units, a thousandth of the rod's "
                             f"slowest vibration period (1.8): a jump, not a sweep; give a "
                             f"rate below {abs(b - a) / SHORTEST_SWEEP:g}, or use jaxrod snap")


def write_scene_sweep(out_dir, s, factor, args) -> None:
    """sweep.csv (the value in the file's units, the tip angle, the tip position in rod
    lengths, snapped, converged; a first comment line when incomplete), sweep.json and
    sweep.png (the tip angle against the value, the snaps marked) of a scene-file sweep."""
    import numpy as np

    v = s.values / factor
    with open(out_dir / "sweep.csv", "w") as fh:
        if not s.complete:
            fh.write(f"# incomplete: {s.reason}\n")
        fh.write(f"{args.vary},tip_angle_deg,tip_x,tip_z,snapped,converged\n")
        for i in range(v.size):
            fh.write(f"{v[i]:.12g},{s.tip_angle_deg[i]:.12g},{s.tip_position[i][0]:.12g},"
                     f"{s.tip_position[i][2]:.12g},{int(s.snapped[i])},"
                     f"{int(s.step_converged[i])}\n")
    (out_dir / "sweep.json").write_text(json.dumps(
        {"rig": args.rig, "set": args.set, "vary": args.vary, "complete": s.complete,
         "reason": s.reason, "converged": s.converged, "points": int(v.size),
         "snaps": [{**snap, "value": snap["value"] / factor} for snap in s.snaps]},
        indent=1))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.plot(v, s.tip_angle_deg, "-", lw=1.2, label="followed")
    snapped = np.asarray(s.snapped, bool)
    if snapped.any():
        ax.plot(v[snapped], s.tip_angle_deg[snapped], "rv", label="snapped (landing)")
    ax.set_xlabel(args.vary)
    ax.set_ylabel("tip angle (deg)")
    ax.legend(fontsize=8)
    fig.savefig(out_dir / "sweep.png", dpi=120)
    plt.close(fig)


def add_rate_sweep_options(w) -> None:
    add_scene_file_inputs(w, vary=False)
    w.add_argument("--vary", metavar="KEY", help="scene file: the input to sweep")
    w.add_argument("--rate", type=_float("rate"), default=None,
                   help="a sweep at a finite rate: the magnet's speed, deg per unit time "
                   "(time in L^2 sqrt(rho A_c / (E I)))")
    w.add_argument("--damping", type=_float("damping"), default=1.0,
                   help="with --rate: the drag per unit length (sqrt(rho A_c E I) / L^2)")
    w.add_argument("--from", dest="start_deg", type=_float("from"), default=None,
                   help="with --rate: the magnet's first angle, deg (scene file: the "
                   "input's first value)")
    w.add_argument("--to", dest="stop_deg", type=_float("to"), default=None,
                   help="with --rate: its last angle, deg (scene file: the last value)")
    w.add_argument("--dt", type=_float("dt"), default=0.5,
                   help="with --rate: the longest time step (default 0.5)")
    w.add_argument("--tol", type=_float("tol"), default=1e-6,
                   help="with --rate: the adaptive steps' local accuracy (default 1e-6; 0: "
                   "fixed steps --dt)")


def _tol(args):
    if not (math.isfinite(args.tol) and args.tol >= 0):
        raise ParameterError(f"tol must be a finite number >= 0, got {args.tol!r}")
    return args.tol or None


def prediction(scene, key, state, stop, rate, damping, n, unit):
    """The first fold a quasi-static sweep of ``key`` from ``state`` to ``stop`` meets, and
    the normal form's switch at ``rate`` (``jaxrod.dynamics.normal_form``), in units of
    ``unit`` (the scene's value of 1 in the user's units); None if it meets no fold."""
    import jaxrod as jr
    from jaxrod.dynamics.normal_form import DAMPED_EXPONENT, INERTIAL_EXPONENT, normal_form

    start = float(scene.value(key))
    folds = jr.folds(scene, key, start, stop, n=n, state=state, throw=False)
    if not folds or not folds[0].converged:
        return None
    nf = normal_form(scene, folds[0], damping, n)
    lag = nf.lag(rate)
    side = math.copysign(1.0, stop - start)
    d, i = nf.damped_prefactor, nf.inertial_prefactor
    return {"fold": nf.value / unit, "switch": (nf.value + side * lag) / unit,
            "lag": lag / unit,
            "damped": {"exponent": DAMPED_EXPONENT, "prefactor": None if math.isinf(d) else
                       d * unit ** (DAMPED_EXPONENT - 1.0)},
            "inertial": {"exponent": INERTIAL_EXPONENT,
                         "prefactor": i * unit ** (INERTIAL_EXPONENT - 1.0)},
            "crossover_rate": nf.crossover_rate / unit, "modal_mass": nf.mass,
            "drive": nf.drive * unit, "curvature": nf.curvature}


def _describe(p, units) -> str:
    if p is None:
        return "the quasi-static sweep meets no fold on the way: no lag predicted"
    u = f" {units}" if units else ""
    return (f"static fold at {p['fold']:.6f}{u}; the fold's normal form: switch at "
            f"{p['switch']:.6f}{u} (lag {p['lag']:.4g}{u}; damped "
            f"{p['damped']['prefactor'] or math.inf:.4g} rate^(2/3), inertial "
            f"{p['inertial']['prefactor']:.4g} rate^(4/5), crossing over at rate "
            f"{p['crossover_rate']:.3g})")


