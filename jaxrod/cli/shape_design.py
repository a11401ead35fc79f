"""``jaxrod design RIG --free KEY [--free KEY ...] --target-shape FILE.csv``: the inputs of a
planar rig whose equilibrium takes a target shape (``jaxrod.inverse.shape_design``)."""

from __future__ import annotations

import json

import numpy as np

from jaxrod.cli.scene_file import _load
from jaxrod.cli.scene_inverse import bounds_of, free_items
from jaxrod.params import ParameterError

#: The target file's columns: s, then the tangent angle, the centreline's point, or both.
COLUMNS = ({"tangent_deg"}, {"x", "z"}, {"x", "z", "tangent_deg"})


def read_target(path: str) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """(s, tangent_deg or None, (x, z) points or None) of a CSV with header ``s,tangent_deg``,
    ``s,x,z`` or ``s,x,z,tangent_deg`` (x, z in rod lengths from the clamp); ParameterError
    naming target-shape where it cannot be read, has NaN, s outside [0, 1] or fewer than 3
    rows."""
    from jaxrod.inverse.shape_design import MIN_POINTS

    try:
        lines = [ln.strip() for ln in open(path, encoding="utf-8") if ln.strip()]
    except OSError as err:
        raise ParameterError(f"target-shape: cannot read {path!r} ({err.strerror})") from None
    header = [c.strip() for c in lines[0].split(",")] if lines else []
    if header[:1] != ["s"] or len(set(header)) != len(header) or set(header[1:]) not in COLUMNS:
        raise ParameterError("target-shape: the first line must be the header s,tangent_deg "
                             "or s,x,z or s,x,z,tangent_deg")
    try:
        rows = np.array([[float(c) for c in ln.split(",")] for ln in lines[1:]], float)
    except ValueError:
        raise ParameterError(f"target-shape: every row must be {len(header)} numbers "
                             f"{','.join(header)}") from None
    if rows.ndim != 2 or rows.shape[1] != len(header) or rows.shape[0] < MIN_POINTS:
        raise ParameterError(f"target-shape: at least {MIN_POINTS} rows of {','.join(header)}")
    if not np.all(np.isfinite(rows)):
        raise ParameterError(f"target-shape: {','.join(header)} must be finite (no NaN)")
    if np.any((rows[:, 0] < 0.0) | (rows[:, 0] > 1.0)):
        raise ParameterError("target-shape: s must lie in [0, 1]")
    col = {name: rows[:, i] for i, name in enumerate(header)}
    return rows[:, 0], col.get("tangent_deg"), \
        np.stack([col["x"], col["z"]], axis=1) if "x" in col else None


def read_tip(text: str) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """``--target-tip X,Z[,DEG]``: the tip's position (rod lengths from the clamp) and,
    optionally, its tangent angle, as a target at s = 1."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) not in (2, 3) or not np.all(np.isfinite(values)):
        raise ParameterError(f"target-tip: X,Z or X,Z,DEG (finite numbers: the tip's position "
                             f"in rod lengths, its tangent angle), got {text!r:.40}")
    return np.ones(1), (np.array(values[2:]) if len(values) == 3 else None), \
        np.array([values[:2]])


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
    if (args.target_shape is None) == (args.target_tip is None):
        raise ParameterError("target-shape: give a target shape (--target-shape FILE.csv) or "
                             "a tip pose (--target-tip X,Z[,DEG]), not both")
    s, target, points = read_target(args.target_shape) if args.target_shape else \
        read_tip(args.target_tip)
    items = free_items(args)
    if not items:
        raise ParameterError("free: name the inputs to solve for (--free KEY, repeatable)")
    keys = free_keys(file, items)
    bounds = bounds_of(args, keys + items)  # a list's key bounds its profile's values
    d = design_shape(file, keys, s, target, n=args.n, bounds=bounds, margin=args.margin,
                     target_xz=points, roughness=args.roughness)
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
            print(f"smallest eigenvalue along the ramp {d.path_smallest_eigenvalue:.6g}: "
                  f"the margin {args.margin:g} {'met' if d.margin_met else 'NOT met'}")
        if d.reason:
            print(d.reason)
        if not d.status.ok:
            print(d.status.message)
        errors = ([f"shape error {d.shape_error_deg:.3g} deg"] if d.target_deg is not None
                  else []) + ([f"position error {d.position_error:.3g} rod lengths"]
                              if d.target_xz is not None else [])
        print(f"{'; '.join(errors)}; {'stable' if d.stable else 'UNSTABLE'}"
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
    if d.target_xz is not None:  # the centreline through its target points
        s = np.linspace(0.0, 1.0, 101)
        from jaxrod.inverse.shape_design import centreline

        x, z = centreline(d, s)
        ax.plot(d.target_xz[:, 0], d.target_xz[:, 1], "ko", ms=4, label="target")
        ax.plot(x, z, "-", color="C0",
                label=f"designed (largest miss {d.position_error:.2g} rod lengths)")
        ax.set_xlabel("x (rod lengths)")
        ax.set_ylabel("z (rod lengths)")
        ax.set_aspect("equal", adjustable="datalim")
    else:
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
