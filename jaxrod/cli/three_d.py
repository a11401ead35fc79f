"""``jaxrod outofplane | track``: three dimensions."""

from __future__ import annotations

import json

from jaxrod.cli._inputs import _float, _magnet_scene_from_args, add_magnet_inputs
from jaxrod.cli._output import _header, _not_converged, _output_dir


def cmd_outofplane(args) -> int:
    import numpy as np

    from jaxrod.discretise.planar import planar_discretisation
    from jaxrod.magnet.diagram import equilibria_at, trace_diagram
    from jaxrod.three_d.outofplane import out_of_plane_at_rows

    scene, info = _magnet_scene_from_args(args)
    branch = trace_diagram(scene, args.n)
    disc = planar_discretisation(args.n, "clamped")
    if args.alpha is None:
        theta, alpha, stable = branch.theta, branch.alpha, branch.stable
    else:
        theta, stable = equilibria_at(scene, branch, np.radians(args.alpha), args.n)
        alpha = np.full(len(stable), np.radians(args.alpha))
    rows = []
    if len(alpha):
        r = out_of_plane_at_rows(theta, alpha, scene, disc)
        for i in range(len(alpha)):
            rows.append({"alpha_deg": float(np.degrees(alpha[i])), "planar_stable": bool(stable[i]),
                         "min_eig_perp": float(r["min_eig_perp"][i]),
                         "min_eig_perp_formula": float(r["min_eig_perp_formula"][i]),
                         "min_eig_plane": float(r["min_eig_plane"][i]),
                         "coupling": float(r["coupling"][i]),
                         "theta_in_0_pi": bool(r["theta_in_0_pi"][i]), "g1": float(r["g1"][i])})
    out = info | {"n": args.n, "points": rows,
                  "min_eig_perp_on_stable": min((x["min_eig_perp"] for x in rows
                                                 if x["planar_stable"]), default=None)}
    if args.json:
        print(json.dumps(out))
        return 0
    print(_header(info) + f": "
          f"{len(rows)} planar equilibria")
    print(f"{'alpha deg':>11} {'planar':>8} {'min eig perp':>13} {'(formula)':>11} "
          f"{'min eig plane':>14} {'coupling':>9}")
    for x in rows:
        print(f"{x['alpha_deg']:11.5f} {'stable' if x['planar_stable'] else 'unstable':>8} "
              f"{x['min_eig_perp']:13.6g} {x['min_eig_perp_formula']:11.6g} "
              f"{x['min_eig_plane']:14.6g} {x['coupling']:9.1e}")
    if out["min_eig_perp_on_stable"] is not None:
        print(f"smallest out-of-plane eigenvalue on planar-stable points: "
              f"{out['min_eig_perp_on_stable']:.6g} (> 0: out-of-plane stable)")
    return 0


def cmd_track(args) -> int:
    from jaxrod.three_d.track import trace_track

    scene, info = _magnet_scene_from_args(args)
    path = _output_dir(args.out) if args.out is not None else None
    track = trace_track(scene, args.alpha0, args.tilt, n=args.n, t_max_deg=args.t_max)
    folds = [{"t_deg": f.t_deg, "tip_angle_deg": f.tip_angle_deg,
              "tip_polar_deg": f.tip_polar_deg, "magnet_polar_deg": f.magnet_polar_deg,
              "magnet_azimuth_deg": f.magnet_azimuth_deg, "rod_azimuth_deg": f.rod_azimuth_deg,
              "hessian_smallest": list(f.hessian_smallest), "converged": f.converged,
              "residual_norm": f.residual_norm} for f in track.folds]
    out = info | {"n": args.n, "alpha0_deg": args.alpha0, "tilt_deg": args.tilt,
                  "t_max_deg": args.t_max, "status": str(track.status[0]), "points": len(track),
                  "max_out_of_plane": float(track.out_of_plane.max()), "folds": folds,
                  "converged": all(f["converged"] for f in folds)}
    if path is not None:
        with open(path / "track.csv", "w") as fh:
            fh.write("t_deg,magnet_polar_deg,magnet_azimuth_deg,tip_x,tip_y,tip_z,stable\n")
            for i in range(len(track)):
                fh.write(f"{track.t_deg[i]:.12g},{track.magnet_polar_deg[i]:.12g},"
                         f"{track.magnet_azimuth_deg[i]:.12g},"
                         + ",".join(f"{c:.12g}" for c in track.tip_position[i])
                         + f",{int(track.stable[i])}\n")
        (path / "track.json").write_text(json.dumps(out, indent=2) + "\n")
    if args.json:
        print(json.dumps(out))
        return 0 if out["converged"] else 1
    print(_header(info) + f": "
          f"magnet from {args.alpha0} deg in the plane along a great circle tilted "
          f"{args.tilt} deg; {len(track)} points ({track.status[0]}); largest out-of-plane "
          f"chart value {out['max_out_of_plane']:.4f} rad")
    for f in folds:
        print(f"fold at t = {f['t_deg']:.10f} deg: magnet polar {f['magnet_polar_deg']:.10f} "
              f"deg, azimuth {f['magnet_azimuth_deg']:.6f} deg; rod azimuth "
              f"{f['rod_azimuth_deg']:.6f} deg{'' if f['converged'] else ' (NOT converged)'}")
    if not folds:
        print("no fold along the track")
    if not out["converged"]:
        _not_converged("track", "a fold refinement did not converge (see the fold lines)")
    return 0 if out["converged"] else 1


def add_outofplane(sub) -> None:
    o = sub.add_parser("outofplane", help="out-of-plane stability of planar equilibria (3D)")
    add_magnet_inputs(o)
    o.add_argument("--alpha", type=_float("alpha", "alpha"), default=None,
                   help="magnet angle (deg): the equilibria at this angle; default: the branch")
    o.add_argument("--branch", action="store_true", help="the whole diagram (the default)")
    o.set_defaults(func=cmd_outofplane)


def add_track(sub) -> None:
    t = sub.add_parser("track", help="3D equilibria and folds along a magnet track that leaves "
                       "the plane")
    add_magnet_inputs(t)
    t.add_argument("--alpha0", type=_float("alpha0", "alpha0"), default=20.0,
                   help="start of the track in the plane, polar angle (deg, in (0, 90))")
    t.add_argument("--tilt", type=_float("tilt", "tilt"), default=90.0,
                   help="angle of the great circle to the meridian (deg; 0: planar track)")
    t.add_argument("--t-max", type=_float("t-max", "t-max"), default=60.0,
                   help="length of the track (deg of arc, in (0, 180])")
    t.add_argument("--out", default=None, help="directory for track.csv and track.json")
    t.set_defaults(func=cmd_track)
