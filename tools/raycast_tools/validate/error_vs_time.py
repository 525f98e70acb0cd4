"""Depth error versus run time per ray: analytic quadrics, tessellations, world form, trimesh.

    .venv/bin/python -m raycast_tools error-vs-time [--rays N] [--segments 16 32 ...]
                                    [--out reports] [--raycast PATH] [--quick]

Writes reports/error_vs_time.md, reports/error_vs_time.png and reports/error_vs_time.json.

Scenes: fixtures/quadrics/ellipsoid.gltf (five transformed ellipsoids, quadrics only),
fixtures/quadrics/mixed.gltf (meshes and quadrics), fixtures/assets/stanford-bunny.obj
(69,451 triangles) and unit spheres far from the origin: fixtures/quadrics/far_sphere.gltf
(6.4e6) plus the same sphere translated to 1e5 and 1e7 (written to a temporary folder).
Rays: rays.py `make_rays` (deterministic, seed 0), unit directions.

Reference ("ref"): quadrics, quadric_reference.py `trace` (float64, object space, stable
roots + one Newton step), checked against `trace_mp` (mpmath, 120 bits) on a subset of
quadric hits; triangles, trimesh `ray_triangle` (float64) picks the nearest triangle and the
depth is recomputed on that triangle's plane with mpmath (120 bits) from the float64 vertex
values.  Rays the references flag as ambiguous (quadric tangent/clip face, ties, hits within
1e-6·scene size of a triangle edge, |cos| < 1e-5) are left out.

Methods (all single-threaded; raycast gets --threads 1):
* raycast, analytic quadrics (or the mesh itself for the bunny);
* raycast on tessellate.py's tessellations (glTF mesh, float32 positions about an anchor);
* trimesh + embree (embreex, float32) on the float64 world-space tessellation;
* trimesh ray_triangle (float64, numpy + rtree) on the tessellation, on a small ray subset;
* numpy "world form": the plain world-space quadric (Q, P, R baked with the node
  translation about the world origin, textbook discriminant L² - 4KM, q-form roots);
* numpy object space (quadric_reference.trace, the float64 reference itself).
raycast has no float32 quadric path: its quadrics are always float64 about a local anchor.

The bound: raycast on each scene itself runs once more with `--aov error` (issue 32), and the
certified bound δ / depth is listed beside the measured error on the same rays; a ray whose
error against the float64 reference exceeds δ is measured again against mpmath (compared in
mpmath, not rounded to float64).

Time per ray: raycast = the sidecar's `trace` seconds / rays (the plot), and separately the
whole process (load + build + trace + write + start-up) / rays; embree and ray_triangle = the
query call after the acceleration structure was built (build listed separately); numpy
methods = the whole vectorised call.  Best of `--repeat` runs.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import mpmath
import numpy as np

from raycast_tools.bench.machine import machine
from raycast_tools.cli import prog
from raycast_tools.fixtures import tessellate as tess
from raycast_tools.paths import ROOT, raycast_or_exit
from raycast_tools.rays import make_rays
from raycast_tools.reference import quadric_reference as qref
from raycast_tools.reference.cast import (
    embree_intersector,
    embree_nearest,
    trace_ray_triangle,
    tri_mesh,
)
from raycast_tools.runner import run_rays
from raycast_tools.validate import validate
from raycast_tools.validate.metrics import edge_distance

FLOOR = 1e-17  # exact agreement is plotted here (log axis)
MP_PREC = 120


# ------------------------------------------------------------------ scenes


def far_sphere_gltf(path: Path, d: float):
    """A unit sphere at (d, 0, 0), like fixtures/quadrics/far_sphere.gltf."""
    h = {
        "asset": {"version": "2.0"},
        "extensionsUsed": [qref.EXT],
        "extensionsRequired": [qref.EXT],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {
                "name": "sphere",
                "translation": [float(d), 0.0, 0.0],
                "extensions": {qref.EXT: {"coefficients": [1.0, 1.0, 1.0, 0, 0, 0, 0, 0, 0, -1.0]}},
            }
        ],
    }
    path.write_text(json.dumps(h, indent=1))
    return path


def scene_list(tmp: Path):
    q = ROOT / "fixtures" / "quadrics"
    return [
        ("ellipsoid", q / "ellipsoid.gltf"),
        ("mixed", q / "mixed.gltf"),
        ("bunny", ROOT / "fixtures" / "assets" / "stanford-bunny.obj"),
        ("sphere@1e5", far_sphere_gltf(tmp / "sphere_1e5.gltf", 1e5)),
        ("far_sphere@6.4e6", q / "far_sphere.gltf"),
        ("sphere@1e7", far_sphere_gltf(tmp / "sphere_1e7.gltf", 1e7)),
    ]


# ------------------------------------------------------------------ references


def _mp_plane_depth(tri, o, u):
    """Depth along unit u from o to the plane of tri, mpmath at MP_PREC bits."""
    import mpmath as mp

    with mp.workprec(MP_PREC):
        v = [[mp.mpf(float(x)) for x in p] for p in tri]
        oo = [mp.mpf(float(x)) for x in o]
        dd = [mp.mpf(float(x)) for x in u]
        e1 = [v[1][k] - v[0][k] for k in range(3)]
        e2 = [v[2][k] - v[0][k] for k in range(3)]
        n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ]
        num = sum((v[0][k] - oo[k]) * n[k] for k in range(3))
        den = sum(dd[k] * n[k] for k in range(3))
        t = num / den
        return float(t * mp.sqrt(sum(x * x for x in dd)))


def mesh_reference(ref, o, u, idx):
    """Nearest-triangle depth/normal for rays idx: ray_triangle + mpmath plane depth."""
    n = len(o)
    depth = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    node = np.full(n, -1, np.int64)
    amb = np.zeros(n, bool)
    f64 = np.full(n, np.inf)
    if len(ref.tris) == 0:
        return depth, normal, node, amb, f64, 0.0
    t0 = time.perf_counter()
    d, _, tri = trace_ray_triangle(ref.tris, o[idx], u[idx])
    t_rt = time.perf_counter() - t0
    f64[idx] = d
    lo, hi = ref.bounds()
    size = float(np.linalg.norm(hi - lo))
    for k, i in enumerate(idx):
        if tri[k] < 0:
            continue
        T = ref.tris[tri[k]]
        dep = _mp_plane_depth(T, o[i], u[i])
        depth[i] = dep
        nrm = ref.normals[tri[k]]
        normal[i] = nrm
        node[i] = ref.objects[ref.tri_obj[tri[k]]].node
        p = o[i] + dep * u[i]
        edge = edge_distance(T[None], p[None])[0]
        if edge < validate.AMBIG["edge_rel"] * size or abs(float(nrm @ u[i])) < 1e-5:
            amb[i] = True
    return depth, normal, node, amb, f64, t_rt


def build_reference(ref, o, u, mesh_idx, n_mp, rng):
    """Merged reference over the rays in `mesh_idx` (all rays when the mesh is small)."""
    n = len(o)
    evalset = np.zeros(n, bool)
    evalset[mesh_idx] = True
    if ref.quadrics:
        qres = qref.trace(ref.quadrics, o, u)
    else:
        qres = {
            "depth": np.full(n, np.inf),
            "normal": np.zeros((n, 3)),
            "node": np.full(n, -1),
            "name": np.array([""] * n, object),
            "index": np.full(n, -1),
            "ambiguous": np.zeros(n, bool),
            "reasons": [set() for _ in range(n)],
        }
    md, mn, mnode, mamb, mf64, t_rt = mesh_reference(ref, o, u, mesh_idx)
    with np.errstate(invalid="ignore"):  # inf - inf in merge_hits' tie test on misses
        merged = qref.merge_hits(qres, md, mn, mnode, mamb)
    out = {
        "depth": merged["depth"],
        "normal": merged["normal"],
        "ambiguous": merged["ambiguous"],
        "kind": merged["kind"],
        "eval": evalset,
        "mesh_depth": md,
        "mesh_f64": mf64,
        "ray_triangle_seconds": t_rt,
        "quadric_depth": qres["depth"],
    }
    # mpmath check of the float64 object-space quadric reference on a subset of quadric hits
    qh = np.flatnonzero(evalset & (merged["kind"] == "quadric") & ~merged["ambiguous"])
    out["mp_idx"] = np.array([], np.int64)
    out["mp_depth"] = np.array([])
    out["mp_vs_f64_max"] = float("nan")
    if ref.quadrics and len(qh):
        sub = np.sort(rng.choice(qh, min(n_mp, len(qh)), replace=False))
        mp = qref.trace_mp(ref.quadrics, o[sub], u[sub], prec=MP_PREC)
        out["mp_idx"] = sub
        out["mp_depth"] = mp["depth"]
        rel = np.abs(qres["depth"][sub] - mp["depth"]) / mp["depth"]
        out["mp_vs_f64_max"] = float(rel.max())
        out["mp_vs_f64_p99"] = float(np.percentile(rel, 99))
    return out


# ------------------------------------------------------------------ methods


def world_form(quadrics):
    """Plain world-space coefficients (Q_w, P_w, R_w) of each quadric, about the world origin."""
    out = []
    for q in quadrics:
        M = np.zeros((4, 4))
        M[:3, :3] = q.Q
        M[:3, 3] = M[3, :3] = 0.5 * q.P
        M[3, 3] = q.R
        Ti = np.linalg.inv(q.world)
        Mw = Ti.T @ M @ Ti
        Mw = 0.5 * (Mw + Mw.T)
        out.append((Mw[:3, :3].copy(), 2.0 * Mw[:3, 3].copy(), float(Mw[3, 3]), q))
    return out


def trace_world_form(wf, o, u):
    """Nearest hit over world-form quadrics: textbook discriminant, q-form roots, clip box
    tested on the local point A⁻¹(w - t).  Returns depth (unit u), normal."""
    n = len(o)
    best = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    for Qw, Pw, Rw, q in wf:
        Qd = u @ Qw
        K = np.einsum("ij,ij->i", u, Qd)
        L = 2.0 * np.einsum("ij,ij->i", o, Qd) + u @ Pw
        M = np.einsum("ij,jk,ik->i", o, Qw, o) + o @ Pw + Rw
        with np.errstate(all="ignore"):
            disc = L * L - 4.0 * K * M
            sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
            qq = -0.5 * (L + np.copysign(sq, L))
            r1, r2 = qq / K, M / qq
            lin = K == 0
            r1 = np.where(lin, -M / L, r1)
            r2 = np.where(lin, np.nan, r2)
            roots = np.sort(np.stack([r1, r2], 1), axis=1)
        t = np.full(n, np.inf)
        for k in range(2):
            tk = roots[:, k]
            ok = np.isfinite(tk) & (tk > 0) & ~np.isfinite(t)
            if q.bmin is not None:
                w = o + np.nan_to_num(tk)[:, None] * u
                pl = (w - q.t) @ q.Ainv.T
                wid = tess.BOX_WIDEN * float(np.max(q.bmax - q.bmin))
                ok &= np.all((pl >= q.bmin - wid) & (pl <= q.bmax + wid), axis=1)
            t[ok] = tk[ok]
        take = t < best
        if take.any():
            w = o[take] + t[take, None] * u[take]
            g = 2.0 * w @ Qw + Pw
            g /= np.linalg.norm(g, axis=1)[:, None]
            normal[take] = g
            best[take] = t[take]
    return best, normal


def timed(fn, repeat):
    best, res = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = fn()
        best = min(best, time.perf_counter() - t0)
    return best, res


def time_embree(tris, o, u, repeat):
    """Embree on the soup: (build seconds, timed by a first one-ray query; best query seconds
    over `repeat` runs; depths of that query)."""
    inter = embree_intersector(tris)
    tb0 = time.perf_counter()
    inter.intersects_id(o[:1], u[:1], multiple_hits=False)
    tbuild = time.perf_counter() - tb0
    te, (de, _) = timed(lambda: embree_nearest(inter, o, u), repeat)
    return tbuild, te, de


def errors(refd, depth, mask):
    """p99/max relative depth error on rays both hit (reference non-ambiguous, in mask)."""
    ok = mask & ~refd["ambiguous"]
    rh = np.isfinite(refd["depth"]) & ok
    mh = np.isfinite(depth)
    both = rh & mh
    rel = np.abs(depth[both] - refd["depth"][both]) / refd["depth"][both]
    hm = int(((np.isfinite(refd["depth"]) != mh) & ok).sum())
    return {
        "hits": int(both.sum()),
        "rays_compared": int(ok.sum()),
        "hitmiss": hm,
        "p99": float(np.percentile(rel, 99)) if len(rel) else float("nan"),
        "max": float(rel.max()) if len(rel) else float("nan"),
        "median": float(np.median(rel)) if len(rel) else float("nan"),
    }


def mp_errors(refd, depth):
    """Error against the mpmath depths on the mp subset."""
    sub = refd["mp_idx"]
    if len(sub) == 0:
        return {}
    d = depth[sub]
    ok = np.isfinite(d)
    rel = np.abs(d[ok] - refd["mp_depth"][ok]) / refd["mp_depth"][ok]
    if not len(rel):
        return {}
    return {
        "mp_p99": float(np.percentile(rel, 99)),
        "mp_max": float(rel.max()),
        "mp_n": int(ok.sum()),
    }


def exact_nearest_depth(quadrics, origin, direction):
    """The nearest quadric crossing's depth of one ray, an mpmath number at MP_PREC bits."""
    depths = [
        qref.intersect_quadric_mp(q, origin, direction, MP_PREC, exact=True)[1] for q in quadrics
    ]
    return min(depths)


# ------------------------------------------------------------------ per scene


def run_scene(label, path, args, raycast, tmp: Path, log):
    rng = np.random.default_rng(1)
    ref = validate.load_reference(path)
    o, u, _ = make_rays(ref, args.rays, seed=0)
    big_mesh = len(ref.tris) > 1000
    n_mesh = min(args.rays, args.mesh_ref_rays) if big_mesh else args.rays
    mesh_idx = np.arange(n_mesh)
    t0 = time.perf_counter()
    refd = build_reference(ref, o, u, mesh_idx, args.mp_rays, rng)
    log(
        f"  reference: {time.perf_counter() - t0:.1f} s, {int(np.isfinite(refd['depth']).sum())} "
        f"hits, {int(refd['ambiguous'].sum())} ambiguous, f64 vs mpmath max "
        f"{refd['mp_vs_f64_max']:.1e}"
    )
    mask = refd["eval"]
    rows = []

    def add(method, family, seconds_per_ray, depth, extra=None, sub=None):
        m = mask if sub is None else (mask & sub)
        r = {
            "scene": label,
            "method": method,
            "family": family,
            "time_per_ray": seconds_per_ray,
            **errors(refd, depth, m),
            **mp_errors(refd, depth),
        }
        if extra:
            r.update(extra)
        rows.append(r)
        log(
            f"  {method:28s} {seconds_per_ray * 1e9:12.0f} ns/ray  p99 {r['p99']:.2e}  "
            f"max {r['max']:.2e}  h/m {r['hitmiss']}"
        )
        return r

    def raycast_run(scene_file, name, family, extra=None, bound=False):
        best_trace, best_wall, res = math.inf, math.inf, None
        # One output folder per run: raycast refuses to write over another scene's outputs.
        work = tmp / f"rc_{label}_{len(rows)}"
        for k in range(args.repeat):
            res = run_rays(raycast, scene_file, o, u, work, threads=1, aov="depth")
            best_trace = min(best_trace, res["sidecar"]["timings"]["trace"])
            best_wall = min(best_wall, res["wall"])
            if res["wall"] > 5.0:  # long runs: one is enough (and keeps the script short)
                break
        if bound:
            extra = {**(extra or {}), **bound_figures(scene_file, res["depth"])}
        tm = res["sidecar"]["timings"]
        ex = {
            "whole_process_per_ray": best_wall / len(o),
            "trace_s": best_trace,
            "wall_s": best_wall,
            "load_s": tm.get("load"),
            "build_s": tm.get("build"),
            "triangles": res["sidecar"].get("stats", {}).get("triangles"),
            "accel": res["sidecar"].get("stats", {}).get("accel"),
        }
        if extra:
            ex.update(extra)
        return add(name, family, best_trace / len(o), res["depth"], ex)

    def bound_figures(scene_file, depth):
        """The certified bound (`--aov error`) on the rays compared, beside the measured error.
        A ray whose error against the float64 reference exceeds its bound is checked again
        against mpmath (the reference has its own ~1e-16 error; mesh depths are mpmath
        already)."""
        res = run_rays(raycast, scene_file, o, u, tmp / f"rb_{label}", threads=1, aov="error")
        bound = res["error"]
        ok = mask & ~refd["ambiguous"] & np.isfinite(refd["depth"]) & np.isfinite(depth)
        rel = bound[ok] / depth[ok]
        over = np.flatnonzero(ok)[bound[ok] < np.abs(depth[ok] - refd["depth"][ok])]
        quadric = over[refd["kind"][over] == "quadric"]
        exceed = len(over) - len(quadric)
        for i in quadric:
            # Compared in mpmath: the exact depth rounded to float64 is itself off by up to half
            # an ulp, about as much as a tight bound allows.
            exact = exact_nearest_depth(ref.quadrics, o[i], u[i])
            with mpmath.workprec(MP_PREC):
                exceed += int(abs(mpmath.mpf(float(depth[i])) - exact) > float(bound[i]))
        return {
            "bound_median": float(np.median(rel)),
            "bound_p99": float(np.percentile(rel, 99)),
            "bound_max": float(rel.max()),
            "bound_over_f64_reference": int(len(over)),
            "bound_exceeded": exceed,
        }

    # raycast on the scene itself, with its certified bound beside the measured error
    raycast_run(
        path,
        "raycast analytic" if ref.quadrics else "raycast (mesh)",
        "raycast analytic" if ref.quadrics else "raycast mesh",
        bound=True,
    )

    if ref.quadrics:
        # numpy object space (the f64 reference itself) and the plain world form
        def merged(dq):
            d = np.minimum(dq, refd["mesh_depth"])
            return d

        t_obj, r_obj = timed(lambda: qref.trace(ref.quadrics, o, u), args.repeat)
        r = add(
            "numpy object space (reference)",
            "numpy object space",
            t_obj / len(o),
            merged(r_obj["depth"]),
            {
                "note": "quadric part timed; mesh hits from the reference; error = vs mpmath "
                "on the subset (against itself it is 0)"
            },
        )
        # the reference cannot measure itself: its error is the one against mpmath
        if "mp_p99" in r:
            r["p99"], r["max"], r["median"] = r["mp_p99"], r["mp_max"], float("nan")
            r["hits"] = r["mp_n"]
        wf = world_form(ref.quadrics)
        t_w, (dw, _) = timed(lambda: trace_world_form(wf, o, u), args.repeat)
        add(
            "numpy world form",
            "numpy world form",
            t_w / len(o),
            merged(dw),
            {"note": "quadric part timed; mesh hits from the reference"},
        )

        # tessellations
        for n in args.segments:
            ts = [tess.tessellate_quadric(q, segments=n) for q in ref.quadrics]
            ttris = tess.triangles_of(ts)
            tris = np.concatenate([ref.tris, ttris]) if len(ref.tris) else ttris
            g = tmp / f"{label}_tess{n}.gltf"
            tess.write_tessellated_gltf(path, g, tessellations=ts)
            extra = {"segments": n, "triangles": int(len(tris))}
            raycast_run(g, f"raycast tess {n}", "raycast tessellated", extra)
            # embree: build on a first call, then time the query
            tbuild, te, de = time_embree(tris, o, u, args.repeat)
            add(
                f"embree tess {n}",
                "trimesh+embree tessellated",
                te / len(o),
                de,
                {**extra, "build_s": tbuild},
            )
            if n <= args.f64_max_segments:
                k = min(args.f64_rays, len(o))
                sub = np.zeros(len(o), bool)
                sub[:k] = True
                from trimesh.ray.ray_triangle import RayMeshIntersector as RT

                rt = RT(tri_mesh(tris))
                tb0 = time.perf_counter()
                rt.intersects_id(o[:1], u[:1], multiple_hits=False)
                tbuild = time.perf_counter() - tb0
                t0 = time.perf_counter()
                d64, _, _ = trace_ray_triangle(tris, o[:k], u[:k])
                trt = time.perf_counter() - t0
                dd = np.full(len(o), np.inf)
                dd[:k] = d64
                add(
                    f"ray_triangle tess {n}",
                    "trimesh ray_triangle tessellated",
                    trt / k,
                    dd,
                    {**extra, "rays_timed": k, "build_s": tbuild},
                    sub=sub,
                )
    else:
        # a real mesh: ray_triangle (the reference run itself) and embree
        k = len(mesh_idx)
        sub = np.zeros(len(o), bool)
        sub[:k] = True
        add(
            "ray_triangle (mesh)",
            "trimesh ray_triangle",
            refd["ray_triangle_seconds"] / k,
            refd["mesh_f64"],
            {"rays_timed": k, "triangles": int(len(ref.tris))},
            sub=sub,
        )
        tbuild, te, de = time_embree(ref.tris, o, u, args.repeat)
        add(
            "embree (mesh)",
            "trimesh+embree",
            te / len(o),
            de,
            {"build_s": tbuild, "triangles": int(len(ref.tris))},
        )
    info = {
        "scene": label,
        "path": str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else path.name,
        "rays": len(o),
        "eval_rays": int(mask.sum()),
        "ref_hits": int((np.isfinite(refd["depth"]) & mask & ~refd["ambiguous"]).sum()),
        "ambiguous": int((refd["ambiguous"] & mask).sum()),
        "mp_rays": int(len(refd["mp_idx"])),
        "mp_vs_f64_max": refd["mp_vs_f64_max"],
        "quadrics": len(ref.quadrics),
        "mesh_triangles": int(len(ref.tris)),
    }
    return rows, info


# ------------------------------------------------------------------ report


def pareto(rows):
    """Rows on the Pareto front (no other row both faster and more accurate), by time."""
    pts = sorted([r for r in rows if np.isfinite(r["p99"])], key=lambda r: r["time_per_ray"])
    front, best = [], math.inf
    for r in pts:
        e = max(r["p99"], FLOOR)
        if e < best:
            front.append(r)
            best = e
    return front


FAMILY_MARKER = {
    "raycast analytic": "*",
    "raycast mesh": "*",
    "raycast tessellated": "o",
    "trimesh+embree tessellated": "s",
    "trimesh+embree": "s",
    "trimesh ray_triangle tessellated": "^",
    "trimesh ray_triangle": "^",
    "numpy world form": "x",
    "numpy object space": "D",
}


def plot(rows, infos, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    scenes = [i["scene"] for i in infos]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    col = {s: colors[k % len(colors)] for k, s in enumerate(scenes)}
    fig, ax = plt.subplots(figsize=(13.5, 7.5))
    for s in scenes:
        rs = [r for r in rows if r["scene"] == s]
        for fam in sorted({r["family"] for r in rs}):
            fr = [r for r in rs if r["family"] == fam]
            x = [r["time_per_ray"] for r in fr]
            y = [max(r["p99"], FLOOR) for r in fr]
            mk = FAMILY_MARKER.get(fam, "o")
            ax.scatter(
                x,
                y,
                marker=mk,
                s=90 if mk == "*" else 36,
                color=col[s],
                facecolors=col[s] if mk not in ("o", "s", "^", "D") else "none",
                linewidths=1.3,
                zorder=3,
            )
            if len(fr) > 1:
                order = np.argsort([r.get("segments", 0) for r in fr])
                ax.plot(
                    np.array(x)[order],
                    np.array(y)[order],
                    color=col[s],
                    lw=0.6,
                    alpha=0.5,
                    zorder=2,
                )
            for r in fr:
                if "segments" in r and fam == "raycast tessellated":
                    ax.annotate(
                        str(r["segments"]),
                        (r["time_per_ray"], max(r["p99"], FLOOR)),
                        fontsize=6,
                        color=col[s],
                        xytext=(3, 3),
                        textcoords="offset points",
                    )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("run time per ray [s] (single thread; raycast: sidecar trace time)")
    ax.set_ylabel("p99 relative depth error on hits (vs float64 object space / mpmath)")
    ax.axhline(FLOOR, color="grey", lw=0.5, ls=":")
    ax.text(
        min(r["time_per_ray"] for r in rows) * 1.05,
        FLOOR * 1.5,
        "exact agreement plotted at 1e-17",
        fontsize=7,
        color="grey",
    )
    ax.grid(True, which="major", alpha=0.3)
    h1 = [Line2D([], [], color=col[s], marker="o", ls="", label=s) for s in scenes]
    fams = [
        "raycast analytic",
        "raycast tessellated",
        "trimesh+embree tessellated",
        "trimesh ray_triangle tessellated",
        "numpy world form",
        "numpy object space",
    ]
    names = [
        "raycast (analytic / mesh)",
        "raycast on tessellation (label = segments)",
        "trimesh + embree",
        "trimesh ray_triangle (f64)",
        "numpy world form",
        "numpy object space (f64 reference; error vs mpmath)",
    ]
    h2 = [
        Line2D(
            [],
            [],
            color="k",
            marker=FAMILY_MARKER[f],
            ls="",
            label=nm,
            markerfacecolor="k" if FAMILY_MARKER[f] in ("*", "x") else "none",
        )
        for f, nm in zip(fams, names)
    ]
    l1 = ax.legend(
        handles=h1, title="scene (colour)", loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8
    )
    ax.add_artist(l1)
    ax.legend(
        handles=h2,
        title="method (marker)",
        loc="upper left",
        bbox_to_anchor=(1.01, 0.55),
        fontsize=8,
    )
    ax.set_title("Depth error vs run time per ray")
    fig.tight_layout()
    fig.savefig(png, dpi=130)
    plt.close(fig)


def binary_id(path: Path):
    import hashlib

    st = path.stat()
    h = hashlib.sha256(path.read_bytes()).hexdigest()[:12]
    return {
        "path": str(path),
        "sha256_12": h,
        "mtime": time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(st.st_mtime)) + " UTC",
    }


def fmt(x, spec=".1e"):
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "—"
    return format(x, spec)


def ns(x):
    return "—" if x is None else (f"{x * 1e9:,.0f}" if x * 1e9 >= 10 else f"{x * 1e9:.1f}")


def summary_text(rows, infos):
    """The computed sentences under the plot."""
    out = []
    by = {}
    for r in rows:
        by.setdefault(r["scene"], []).append(r)
    # Pareto fronts
    out.append(
        "**Pareto front per scene** (no other method both faster and more accurate, fastest first):"
    )
    out.append("")
    for s, rs in by.items():
        front = pareto(rs)
        out.append(
            f"- {s}: "
            + " → ".join(
                f"{r['method']} ({ns(r['time_per_ray'])} ns, {fmt(r['p99'])})" for r in front
            )
        )
    out.append("")
    # the certified bound beside the measured error
    out.append(
        "**Certified bound beside the measured error** (raycast on the scene itself, "
        "`--aov error`: δ with |depth − exact depth| ≤ δ, docs/buffers-and-cli.md; relative "
        "to depth, on the rays compared; a ray whose error against the float64 reference "
        "exceeds δ is measured again against mpmath, since that reference is itself off by "
        "~1e-16, and compared in mpmath: the exact depth rounded to float64 is off by up to half "
        "an ulp, about as much as a tight bound allows; the cost of the bound, in instruction "
        "counts: reports/error_bounds.md, Cost):"
    )
    out.append("")
    for s, rs in by.items():
        for r in rs:
            if "bound_median" not in r:
                continue
            out.append(
                f"- {s}, {r['method']}: measured p99 {fmt(r['p99'])} (median "
                f"{fmt(r['median'])}, max {fmt(r['max'])}); bound median "
                f"{fmt(r['bound_median'])}, p99 {fmt(r['bound_p99'])}, max {fmt(r['bound_max'])}; "
                f"error above the bound against the float64 reference on "
                f"{r['bound_over_f64_reference']} rays, against mpmath on "
                f"{r['bound_exceeded']}."
            )
    out.append("")
    # tessellation pay-off
    out.append("**Where tessellation stops paying off.**")
    out.append("")
    for s, rs in by.items():
        an = [r for r in rs if r["family"] == "raycast analytic"]
        tr = sorted(
            [r for r in rs if r["family"] == "raycast tessellated"], key=lambda r: r["segments"]
        )
        if not an or not tr:
            continue
        a = an[0]
        ea = max(a["p99"], 1e-16)
        match = [r for r in tr if r["p99"] <= max(a["p99"], FLOOR) * 1.0001]
        slower = [r for r in tr if r["time_per_ray"] > a["time_per_ray"]]
        last = tr[-1]
        # e² law: p99 ∝ n⁻², triangles ∝ n²
        nneed = last["segments"] * math.sqrt(max(last["p99"], FLOOR) / ea)
        tri_need = last["triangles"] * (nneed / last["segments"]) ** 2
        emb = sorted(
            [r for r in rs if r["family"] == "trimesh+embree tessellated"],
            key=lambda r: r["segments"],
        )
        emb_fast = [r for r in emb if r["time_per_ray"] < a["time_per_ray"]]
        txt = (
            f"- {s}: raycast analytic p99 {fmt(a['p99'])} at {ns(a['time_per_ray'])} ns/ray "
            f"(whole process {ns(a.get('whole_process_per_ray'))} ns/ray). "
        )
        if match:
            m = match[0]
            txt += (
                f"The tessellation matches it from {m['segments']} segments "
                f"({m['triangles']:,} triangles, {ns(m['time_per_ray'])} ns/ray). "
            )
        else:
            txt += (
                f"No tessellation matches it: the finest, {last['segments']} segments "
                f"({last['triangles']:,} triangles), has p99 {fmt(last['p99'])} at "
                f"{ns(last['time_per_ray'])} ns/ray trace "
                f"(+{fmt(last.get('build_s'), '.1f')} s build); by the e² law matching would need "
                f"≈{nneed:.0e} segments "
                f"(≈{tri_need:.0e} triangles). "
            )
        if slower:
            txt += (
                f"raycast on its tessellation is slower per ray than on the analytic "
                f"quadrics from {slower[0]['segments']} segments on"
            )
            if len(slower) == len(tr):
                txt += " (every resolution tried)"
            txt += f", {last['time_per_ray'] / a['time_per_ray']:.0f}× at {last['segments']}. "
        else:
            txt += "raycast on its tessellation stays at or below the analytic trace time here. "
        if emb_fast:
            e = emb_fast[-1]
            txt += (
                f"Only trimesh + embree on the tessellation is faster per ray than raycast "
                f"analytic, up to {e['segments']} segments ({ns(e['time_per_ray'])} ns/ray), "
                f"at p99 {fmt(e['p99'])}: {math.log10(max(e['p99'], FLOOR) / ea):.0f} digits "
                f"worse."
            )
        else:
            txt += "No tessellated method is faster per ray than raycast analytic here."
        out.append(txt)
    out.append("")
    # world form
    out.append(
        "**World form (Q, P, R baked about the world origin) versus object space**, "
        "near and far from the origin (p99 relative depth error; digits lost = "
        "log10(world / object space), object space error vs mpmath, floored at 1e-16):"
    )
    out.append("")
    for s, rs in by.items():
        w = [r for r in rs if r["family"] == "numpy world form"]
        ob = [r for r in rs if r["family"] == "numpy object space"]
        an = [r for r in rs if r["family"] == "raycast analytic"]
        if not w:
            continue
        eo = ob[0].get("mp_p99", ob[0]["p99"]) if ob else float("nan")
        lost = math.log10(max(w[0]["p99"], 1e-16) / max(eo, 1e-16))
        out.append(
            f"- {s}: world form p99 {fmt(w[0]['p99'])} (max {fmt(w[0]['max'])}, "
            f"hit/miss disagreements {w[0]['hitmiss']}), object space vs mpmath "
            f"{fmt(eo)}, raycast {fmt(an[0]['p99']) if an else '—'}: "
            f"{lost:.1f} digits lost."
        )
    return "\n".join(out)


def stiff_table() -> str:
    """Every stiff and extreme case with its measured error and bound, from the Rust test
    tests/it/stiff.rs (expected values: mpmath at 200 bits, fixtures/stiff/cases.json)."""
    with tempfile.TemporaryDirectory(prefix="stiff") as td:
        table = Path(td) / "stiff.md"
        env = dict(os.environ, RAYCAST_STIFF_REPORT=str(table))
        run = subprocess.run(
            ["cargo", "test", "--release", "--quiet", "--test", "stiff"],
            cwd=ROOT,
            env=env,
            capture_output=True,
            text=True,
        )
        if run.returncode != 0 or not table.exists():
            return (
                "**The stiff-case test failed** (`cargo test --release --test it stiff::`):\n\n"
                "```\n" + (run.stdout + run.stderr)[-3000:] + "\n```"
            )
        return table.read_text()


def write_report(rows, infos, mach, args, elapsed, md_path, png_path, stiff):
    L = []
    L.append("# Depth error versus run time per ray")
    L.append("")
    L.append(
        "Regenerate: `.venv/bin/python -m raycast_tools error-vs-time` (writes this file, "
        f"`{png_path.name}` and `error_vs_time.json`; took {elapsed:.0f} s)."
    )
    L.append("")
    la = mach["loadavg"]
    L.append(
        f"Machine: {mach['nproc']} CPUs (`nproc`), {mach['cpu']}"
        f"{f' at {mach[chr(109) + chr(104) + chr(122)]:.0f} MHz' if mach['mhz'] else ''}, "
        f"load average at start {la[0]:.2f}/{la[1]:.2f}/{la[2]:.2f} (a shared machine: two "
        f"earlier full runs of this script differed by up to 4× on single raycast points, "
        f"so read time differences below that factor with care). Python {mach['python']}, numpy "
        f"{mach['numpy']}. "
        "Everything single-threaded (raycast `--threads 1`)."
    )
    L.append("")
    b0 = mach.get("binary_start", {})
    accel = sorted({str(r.get("accel")) for r in rows if r.get("accel")})
    L.append(
        f"raycast binary: `{b0.get('path')}` (copied at the start and run from the copy), "
        f"sha256 {b0.get('sha256_12')}…, built {b0.get('mtime')}; acceleration structure "
        f"reported in the sidecar: {', '.join(accel) or '—'}."
    )
    L.append("")
    L.append(f"![error vs time]({png_path.name})")
    L.append("")
    L.append(
        "Each marker is one method (or one tessellation resolution) on one scene: x = run "
        "time per ray, y = p99 relative depth error on rays both the method and the "
        "reference hit (exact agreement is drawn at 1e-17). Lower left is better."
    )
    L.append("")
    L.append(summary_text(rows, infos))
    L.append("")
    L.append(
        "**Notes.** raycast has no float32 quadric path (its quadrics are always float64 "
        "about a local anchor, docs/RAYCAST_quadric.md), so the float precision question "
        "for quadrics is shown with the numpy world form instead. The tessellation error "
        "is the chordal (sagitta) error, ≈ e²/(8r) for edge length e on curvature radius "
        "r, divided by the incidence cosine; it falls as e² (see "
        "`python -m raycast_tools tessellation-check` for the fitted slopes), so each halving of "
        "the "
        "error costs about 1.4× the segments and 2× the triangles. p99 includes the "
        "silhouette and open-rim rays where a chord sends the ray to another facet; hit/"
        "miss disagreements are counted separately (column h/m) and not in the error. "
        "ray_triangle's p99 on the tessellations comes from its small ray subset (about "
        "half of them hit, so it is nearly the max of those and misses most silhouette "
        "rays): compare it with the others' median rather than their p99. trimesh + "
        "embree traverses in float32 but trimesh recomputes each hit point in float64 on "
        "the plane of the triangle Embree found, so its depth error is the float64 one "
        "whenever the triangle is right (bunny: the same p99 as ray_triangle; far "
        "spheres: the same as raycast's tessellation, the sagitta dominating). raycast "
        "stores triangle vertices in float32 about an anchor, which is the ~1e-7 error on "
        "the bunny (`python -m raycast_tools validate` allows a p99 of 1e-6)."
    )
    L.append("")
    L.append("## Scenes and references")
    L.append("")
    L.append(
        "| scene | file | rays (timed) | rays with reference | reference hits | ambiguous "
        "| quadrics | mesh triangles | mpmath subset | f64 ref vs mpmath, max rel |"
    )
    L.append("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for i in infos:
        L.append(
            f"| {i['scene']} | `{i['path']}` | {i['rays']} | {i['eval_rays']} | "
            f"{i['ref_hits']} | {i['ambiguous']} | {i['quadrics']} | {i['mesh_triangles']:,} "
            f"| {i['mp_rays']} | {fmt(i['mp_vs_f64_max'])} |"
        )
    L.append("")
    L.append(
        "The float64 object-space reference agrees with mpmath (120 bits) to the value in "
        "the last column on the subset; the bunny's (and the mixed scene's mesh) "
        "reference depths are mpmath plane intersections on the triangle ray_triangle "
        "found, so ray_triangle's own float64 error is measurable. The sphere@1e5 and "
        "sphere@1e7 scenes are far_sphere.gltf's unit sphere moved to (1e5,0,0) and "
        "(1e7,0,0), written to a temporary folder."
    )
    L.append("")
    L.append("## All measurements")
    L.append("")
    L.append(
        "Time columns in ns per ray. *trace*: raycast sidecar `trace` (the plotted value "
        "for raycast); *process*: raycast whole-process wall time / rays; for other "
        "methods the query call (after building the acceleration structure, *build*). "
        "ray_triangle is timed on the first rays only (column *rays timed*)."
    )
    L.append("")
    L.append(
        "| scene | method | triangles | time/ray (plotted) | raycast process/ray | build s "
        "| rays timed | hits | h/m | median | p99 | max | vs mpmath p99 | vs mpmath max |"
    )
    L.append("|" + " --- |" * 14)
    for r in rows:
        L.append(
            f"| {r['scene']} | {r['method']} | {r.get('triangles') or '—'} | "
            f"{ns(r['time_per_ray'])} | {ns(r.get('whole_process_per_ray'))} | "
            f"{fmt(r.get('build_s'), '.3f')} | {r.get('rays_timed', '—')} | {r['hits']} | "
            f"{r['hitmiss']} | {fmt(r['median'])} | {fmt(r['p99'])} | {fmt(r['max'])} | "
            f"{fmt(r.get('mp_p99'))} | {fmt(r.get('mp_max'))} |"
        )
    L.append("")
    L.append(
        f"Settings: {args.rays} rays per scene (raycast_tools.rays `make_rays`, seed 0), "
        f"tessellations {args.segments} segments around (ellipsoids: half as many rings), "
        f"ray_triangle on {args.f64_rays} rays up to {args.f64_max_segments} segments, "
        f"bunny reference on {args.mesh_ref_rays} rays, mpmath on {args.mp_rays} quadric "
        f"hits per scene, best of {args.repeat} runs."
    )
    L.append("")
    L.append("## Stiff and extreme cases")
    L.append("")
    L.append(
        "From `cargo test --release --test it stiff::` (tests/it/stiff.rs), which checks each "
        "case of `fixtures/stiff/cases.json` against its expected value, computed offline in "
        "mpmath at 200 bits by `python -m raycast_tools stiff-cases`, and against the case's own "
        "bound (derivations "
        "in `fixtures/stiff/README.md`; near tangency the bound scales with the root's "
        "condition, and ambiguous cases accept either a hit or a miss). *result* is the "
        "depth raycast computed, or what happened; the test fails if any case leaves its "
        "bound."
    )
    L.append("")
    L.append(stiff)
    md_path.write_text("\n".join(L) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(prog=prog("error-vs-time"), description=__doc__.split("\n")[0])
    ap.add_argument("--rays", type=int, default=20000)
    ap.add_argument("--segments", nargs="+", type=int, default=[16, 32, 64, 128, 256, 512])
    ap.add_argument("--f64-rays", type=int, default=100)
    ap.add_argument("--f64-max-segments", type=int, default=64)
    ap.add_argument("--mesh-ref-rays", type=int, default=400)
    ap.add_argument("--mp-rays", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenes", nargs="*", default=None, help="labels to run (default all)")
    ap.add_argument("--out", default=str(ROOT / "reports"))
    ap.add_argument("--raycast", default=None)
    ap.add_argument("--quick", action="store_true", help="few rays and resolutions (smoke test)")
    a = ap.parse_args(argv)
    if a.quick:
        a.rays, a.segments, a.f64_rays, a.mesh_ref_rays, a.mp_rays, a.repeat = (
            2000,
            [16, 64],
            30,
            60,
            20,
            1,
        )
    raycast = raycast_or_exit(a.raycast, "error-vs-time")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    mach = machine()
    t0 = time.perf_counter()
    rows, infos = [], []
    with tempfile.TemporaryDirectory(prefix="evt") as td:
        tmp = Path(td)
        # run a private copy, so that a rebuild of target/release during the run cannot mix
        # two binaries in one report
        private = tmp / "raycast"
        shutil.copy2(raycast, private)
        mach["binary_start"] = binary_id(private)
        mach["binary_start"]["path"] = str(raycast)
        raycast = private
        for label, path in scene_list(tmp):
            if a.scenes and label not in a.scenes:
                continue
            ts = time.perf_counter()
            print(f"{label}: {path.name}", flush=True)
            r, info = run_scene(label, path, a, raycast, tmp, lambda s: print(s, flush=True))
            info["seconds"] = time.perf_counter() - ts
            print(f"  ({info['seconds']:.0f} s)", flush=True)
            rows += r
            infos.append(info)
    elapsed = time.perf_counter() - t0
    png = out / "error_vs_time.png"
    plot(rows, infos, png)
    write_report(rows, infos, mach, a, elapsed, out / "error_vs_time.md", png, stiff_table())
    (out / "error_vs_time.json").write_text(
        json.dumps(
            {"machine": mach, "scenes": infos, "rows": rows, "seconds": elapsed},
            indent=1,
            default=lambda x: x.item() if hasattr(x, "item") else str(x),
        )
    )
    print(f"wrote {out / 'error_vs_time.md'}, {png} ({elapsed:.0f} s)")
    return 0
