#!/usr/bin/env python3
"""The template made from one frame's points, the product's beside Screened Poisson (Open3D,
Kazhdan & Hoppe 2013, then quadric decimation to the same vertex count), in one run, against the
true surface the points were captured from:

    BenchmarkTemplate.py --cloud FRAME.ply --truth TRUE.ply [--cloud ... --truth ...]
                         [--vertices 1000] [--poisson-depth 9] [--scale METRES_PER_UNIT]
                         [--product build/bin/TemplateFromCloud] [--keep DIR]

Per template: the distance to the true surface both ways (RMS and 95th percentile, mm: the
template's vertices and 50 000 samples of it to the truth; 50 000 samples of the truth to it),
its pieces, Euler characteristic and genus (closed pieces), boundary and non-manifold edges,
folded edges (interior edges whose faces turn more than 120 degrees), slivers (triangles with an
angle under 5 degrees), time. --scale: metres per unit of the files (a simulated rig's rig.json
says it); default 1.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import open3d as o3d


def parse():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--cloud", action="append", required=True)
    p.add_argument("--truth", action="append", required=True)
    p.add_argument("--vertices", type=int, default=1000)
    p.add_argument("--poisson-depth", type=int, default=9)
    p.add_argument("--scale", type=float, default=0)
    p.add_argument("--product", default=os.path.join(os.path.dirname(__file__), "..", "..",
                                                     "build", "bin", "TemplateFromCloud"))
    p.add_argument("--keep", help="write each template here")
    p.add_argument("--no-poisson", action="store_true", help="the product's template alone")
    a = p.parse_args()
    if len(a.cloud) != len(a.truth):
        p.error("give one --truth per --cloud")
    return a


def topology(mesh):
    """Pieces, Euler characteristic, genus of the closed pieces, boundary, non-manifold,
    folded edges and slivers of a triangle mesh."""
    tri = np.asarray(mesh.triangles)
    v = np.asarray(mesh.vertices)
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    faces_of = np.repeat(np.arange(len(tri)), 1)
    keys, inverse, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    used = np.unique(tri)
    chi = len(used) - len(keys) + len(tri)
    clusters, sizes, _ = mesh.cluster_connected_triangles()
    pieces = len(sizes)
    boundary = int((counts == 1).sum())
    nonmanifold = int((counts > 2).sum())
    genus = (2 * pieces - chi) / 2 if boundary == 0 else float("nan")
    # Folded: the two faces of an interior edge turn more than 120 degrees.
    n = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    face_of_edge = np.tile(np.arange(len(tri)), 3)
    order = np.argsort(inverse, kind="stable")
    first = np.full(len(keys), -1)
    second = np.full(len(keys), -1)
    seen = np.zeros(len(keys), dtype=int)
    for e, f in zip(inverse[order], face_of_edge[order]):
        if seen[e] == 0:
            first[e] = f
        elif seen[e] == 1:
            second[e] = f
        seen[e] += 1
    interior = (counts == 2)
    cosines = (n[first[interior]] * n[second[interior]]).sum(axis=1)
    folded = float((cosines < np.cos(np.radians(120))).mean()) if interior.any() else 0.0
    # Slivers: an angle under 5 degrees.
    angles = []
    for i in range(3):
        a, b, c = tri[:, i], tri[:, (i + 1) % 3], tri[:, (i + 2) % 3]
        u, w = v[b] - v[a], v[c] - v[a]
        cos = (u * w).sum(1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1),
                                          1e-300)
        angles.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    slivers = float((np.min(angles, axis=0) < 5).mean())
    return dict(vertices=len(used), triangles=len(tri), pieces=pieces, euler=chi, genus=genus,
                boundary=boundary, nonmanifold=nonmanifold, folded=folded, slivers=slivers)


def distances(mesh, truth, scale):
    """RMS and 95th percentile (mm) of the template's distance to the truth and back."""
    def scene_of(m):
        s = o3d.t.geometry.RaycastingScene()
        s.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(m))
        return s
    to_truth = scene_of(truth)
    to_mesh = scene_of(mesh)
    mesh_samples = np.concatenate([np.asarray(mesh.vertices),
                                   np.asarray(mesh.sample_points_uniformly(50000).points)])
    truth_samples = np.asarray(truth.sample_points_uniformly(50000).points)
    there = to_truth.compute_distance(o3d.core.Tensor(mesh_samples, o3d.core.float32)).numpy()
    back = to_mesh.compute_distance(o3d.core.Tensor(truth_samples, o3d.core.float32)).numpy()
    mm = 1000 * scale
    return dict(rms_to_truth=mm * np.sqrt((there ** 2).mean()),
                p95_to_truth=mm * np.percentile(there, 95),
                rms_from_truth=mm * np.sqrt((back ** 2).mean()),
                p95_from_truth=mm * np.percentile(back, 95))


def product_template(args, cloud, out):
    start = time.perf_counter()
    run = subprocess.run([args.product, cloud, out, str(args.vertices)], capture_output=True,
                         text=True)
    if run.returncode != 0:
        sys.exit(f"TemplateFromCloud failed: {run.stderr}")
    return o3d.io.read_triangle_mesh(out), time.perf_counter() - start


def poisson_template(args, cloud):
    start = time.perf_counter()
    points = o3d.io.read_point_cloud(cloud)
    if not points.has_normals():
        points.estimate_normals()
        points.orient_normals_consistent_tangent_plane(16)
    mesh, _ = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(
        points, depth=args.poisson_depth)
    mesh = mesh.simplify_quadric_decimation(2 * args.vertices)
    mesh.remove_unreferenced_vertices()
    return mesh, time.perf_counter() - start


def main():
    args = parse()
    o3d.utility.random.seed(1)  # the same samples every run
    scratch = args.keep or tempfile.mkdtemp(prefix="dp-template-")
    os.makedirs(scratch, exist_ok=True)
    print(f"{'cloud':<28} {'template':<14} {'V':>5} {'pieces':>6} {'genus':>5} {'bound.':>6} "
          f"{'non-m.':>6} {'folded %':>8} {'sliver %':>8} {'to truth mm':>14} {'from truth mm':>14}"
          f" {'s':>6}")
    for i, (cloud, truth_path) in enumerate(zip(args.cloud, args.truth)):
        scale = args.scale
        if not scale:
            rig = os.path.join(os.path.dirname(cloud), "rig.json")
            scale = json.load(open(rig))["metresPerUnit"] if os.path.exists(rig) else 1.0
        truth = o3d.io.read_triangle_mesh(truth_path)
        results = [("product",) + product_template(args, cloud,
                                                   os.path.join(scratch, f"product_{i}.ply"))]
        if not args.no_poisson:
            results.append((f"poisson d{args.poisson_depth}",) + poisson_template(args, cloud))
        for name, mesh, seconds in results:
            if args.keep:
                o3d.io.write_triangle_mesh(os.path.join(scratch, f"{name.split()[0]}_{i}.ply"), mesh)
            t = topology(mesh)
            d = distances(mesh, truth, scale)
            label = os.path.join(os.path.basename(os.path.dirname(cloud)), os.path.basename(cloud))
            print(f"{label[-28:]:<28} {name:<14} {t['vertices']:>5} {t['pieces']:>6} "
                  f"{t['genus']:>5.0f} {t['boundary']:>6} {t['nonmanifold']:>6} "
                  f"{100 * t['folded']:>8.2f} {100 * t['slivers']:>8.2f} "
                  f"{d['rms_to_truth']:>6.2f} / {d['p95_to_truth']:<5.1f} "
                  f"{d['rms_from_truth']:>6.2f} / {d['p95_from_truth']:<5.1f} {seconds:>6.2f}")


if __name__ == "__main__":
    main()
