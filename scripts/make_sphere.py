#!/usr/bin/env python3
"""Writes scenes/glossy-spheres/models/sphere.obj: a unit sphere as a triangle mesh (latitude-longitude grid)
with per-vertex normals and longitude-latitude texture coordinates, for the GLOSSY SPHERES scene of the manifold perturbation's glossy extension. The
spheres are meshes on purpose: a triangle's chart does not turn within its tangent plane, which the specular
constraint's Jacobian assumes for glossy vertices (common/manifold/manifold_walk.h). Deterministic: rerunning
gives the same bytes.

    python3 scripts/make_sphere.py [--stacks 24] [--slices 48] [-o PATH]
"""
import argparse
import math
import os


def sphere(stacks, slices):
    """Vertices (= normals), texture coordinates and triangles of (vertex, texture coordinate) index pairs
    (0-based, counter-clockwise seen from outside). The texture coordinates are longitude and latitude, so that
    dp/du of neighbouring triangles points nearly the same way (the seam at u = 1 gets its own coordinates)."""
    vertices = [(0.0, 1.0, 0.0)]
    for i in range(1, stacks):
        theta = math.pi * i / stacks
        for j in range(slices):
            phi = 2 * math.pi * j / slices
            vertices.append((math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi)))
    vertices.append((0.0, -1.0, 0.0))
    bottom = len(vertices) - 1
    # (slices + 1) texture coordinates per ring 0 .. stacks; the poles' use the middle of their triangle.
    uvs = [((j + (0.5 if i in (0, stacks) else 0.0)) / slices, 1 - i / stacks)
           for i in range(stacks + 1) for j in range(slices + 1)]

    def ring(i, j):
        return 1 + (i - 1) * slices + j % slices

    def uv(i, j):
        return i * (slices + 1) + j

    triangles = []
    for j in range(slices):
        triangles.append(((0, uv(0, j)), (ring(1, j), uv(1, j)), (ring(1, j + 1), uv(1, j + 1))))
        triangles.append(((bottom, uv(stacks, j)), (ring(stacks - 1, j + 1), uv(stacks - 1, j + 1)),
                          (ring(stacks - 1, j), uv(stacks - 1, j))))
    for i in range(1, stacks - 1):
        for j in range(slices):
            a, b = (ring(i, j), uv(i, j)), (ring(i + 1, j), uv(i + 1, j))
            c, d = (ring(i + 1, j + 1), uv(i + 1, j + 1)), (ring(i, j + 1), uv(i, j + 1))
            triangles.append((a, b, c))
            triangles.append((a, c, d))
    return vertices, uvs, triangles


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stacks", type=int, default=24)
    parser.add_argument("--slices", type=int, default=48)
    here = os.path.dirname(os.path.abspath(__file__))
    parser.add_argument("-o", default=os.path.join(here, "..", "scenes", "glossy-spheres", "models", "sphere.obj"))
    args = parser.parse_args()
    vertices, uvs, triangles = sphere(args.stacks, args.slices)
    os.makedirs(os.path.dirname(os.path.abspath(args.o)), exist_ok=True)
    with open(args.o, "w", newline="\n") as out:
        out.write(f"# unit sphere, {args.stacks} stacks x {args.slices} slices (scripts/make_sphere.py)\n")
        for v in vertices:
            out.write("v %.9f %.9f %.9f\n" % v)
        for t in uvs:
            out.write("vt %.9f %.9f\n" % t)
        for v in vertices:
            out.write("vn %.9f %.9f %.9f\n" % v)
        for t in triangles:
            out.write("f " + " ".join(f"{k + 1}/{u + 1}/{k + 1}" for k, u in t) + "\n")


if __name__ == "__main__":
    main()
