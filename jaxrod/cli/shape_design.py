"""``jaxrod design RIG --free KEY [--free KEY ...] --target-shape FILE.csv``: the inputs of a
planar rig whose equilibrium takes a target shape (``jaxrod.inverse.shape_design``)."""

from __future__ import annotations

import json

import numpy as np

from jaxrod.cli.scene_file import _load
from jaxrod.cli.scene_inverse import bounds_of, free_items
from jaxrod.params import ParameterError


def read_target(path: str) -> tuple[np.ndarray, np.ndarray]:
    """(s, tangent_deg) of a CSV with header ``s,tangent_deg``; ParameterError naming
    target-shape where it cannot be read, has NaN, s outside [0, 1] or fewer than 3 rows."""
    from jaxrod.inverse.shape_design import MIN_POINTS

    try:
        lines = [ln.strip() for ln in open(path, encoding="utf-8") if ln.strip()]
    except OSError as err:
        raise ParameterError(f"target-shape: cannot read {path!r} ({err.strerror})") from None
    if not lines or [c.strip() for c in lines[0].split(",")] != ["s", "tangent_deg"]:
        raise ParameterError("target-shape: the first line must be the header s,tangent_deg")
    try:
        rows = np.array([[float(c) for c in ln.split(",")] for ln in lines[1:]], float)
    except ValueError:
        raise ParameterError("target-shape: every row must be two numbers s,tangent_deg") \
            from None
    if rows.ndim != 2 or rows.shape[1] != 2 or rows.shape[0] < MIN_POINTS:
        raise ParameterError(f"target-shape: at least {MIN_POINTS} rows of s,tangent_deg")
    if not np.all(np.isfinite(rows)):
        raise ParameterError("target-shape: s and tangent_deg must be finite (no NaN)")
    if np.any((rows[:, 0] < 0.0) | (rows[:, 0] > 1.0)):
        raise ParameterError("target-shape: s must lie in [0, 1]")
    return rows[:, 0], rows[:, 1]


def free_keys(file, keys) -> list[str]:
    """The free keys, a list's key (``magnetisation.strength_profile``) expanded to its
    coefficients' keys (the file's numbers below it, ``jaxrod.scenes.path.numeric_keys``)."""
    from jaxrod.scenes.path import numeric_keys

    numbers = numeric_keys(file.data)
    out = []
    for key in keys:
        below = [k for k in numbers if k.startswith(key + ".") and
                 k[len(key) + 1:].isdigit()]
        out += below or [key]
    return out


def _profile(file, s) -> dict | None:
    """The remanence load along s, load mu(s), of the rig's programmed magnetisation."""
    terms = [t for t in file.scene.terms.values() if hasattr(t, "mu")]
    if len(terms) != 1:
        return None
    t = terms[0]
    return {"s": s.tolist(), "strength": (float(t.load) * np.asarray(t.mu(s))).tolist(),
            "angle_deg": np.degrees(np.asarray(t.phi(s)) * np.ones_like(s)).tolist()}


def shape_on_file(args) -> int:
    from jaxrod.inverse.shape_design import design_shape

    file = _load(args)
    s, target = read_target(args.target_shape)
    items = free_items(args)
    if not items:
        raise ParameterError("free: name the inputs to solve for (--free KEY, repeatable)")
    keys = free_keys(file, items)
    bounds = bounds_of(args, keys + items)  # a list's key bounds its profile's values
    d = design_shape(file, keys, s, target, n=args.n, bounds=bounds, margin=args.margin)
    out = {"rig": args.rig, "free": keys, **d.as_dict(),
           "profile": _profile(d.scene, np.linspace(0.0, 1.0, 101))}
    if args.out:
        from jaxrod.cli._output import _output_dir

        out_dir = _output_dir(args.out)
        (out_dir / "design.json").write_text(json.dumps(out, indent=1))
        _figure(out_dir / "shape.png", d, out["profile"])
    if args.json:
        print(json.dumps(out))
    else:
        for k, v in d.values.items():
            print(f"{k} = {v:.10g}")
        if args.margin > 0.0:
            print(f"smallest Hessian eigenvalue {d.smallest_eigenvalue:.6g}: the margin "
                  f"{args.margin:g} {'met' if d.margin_met else 'NOT met'}")
        if d.reason:
            print(d.reason)
        if not d.status.ok:
            print(d.status.message)
        print(f"shape error {d.shape_error_deg:.3g} deg; {'stable' if d.stable else 'UNSTABLE'}"
              f"; {'reached' if d.reachable else 'NOT reached'} by ramping the loads; "
              f"converged: {d.converged}")
    return 0 if d.status.ok and d.reached else 1


def _figure(path, d, profile) -> None:
    """The target and the achieved tangent angle against s, and the designed profile."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2 if profile else 1, figsize=(10 if profile else 5.5, 4),
                             squeeze=False)
    ax = axes[0][0]
    ax.plot(d.s, d.target_deg, "ko", ms=4, label="target")
    ax.plot(d.s, d.tangent_deg, "-", color="C0",
            label=f"designed (largest error {d.shape_error_deg:.2g} deg)")
    ax.set_xlabel("s (rod lengths)")
    ax.set_ylabel("tangent angle (deg)")
    ax.legend(fontsize=8)
    if profile:
        ax = axes[0][1]
        ax.plot(profile["s"], profile["strength"], "-", color="C3")
        ax.set_xlabel("s (rod lengths)")
        ax.set_ylabel("remanence load, load mu(s)")
        ax.set_title("designed profile", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
