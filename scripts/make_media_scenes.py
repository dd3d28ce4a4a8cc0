#!/usr/bin/env python3
"""Writes the generated parts of the two media scenes of manifold exploration through participating media
(ALGORITHMS.md §6.7):

* scenes/glass-egg/models/egg.obj: the egg of the GLASSEGG scene (scenes/glass-egg/scene.xml, after Jakob &
  Marschner 2012, Fig. 14), an egg of revolution about +y with per-vertex normals of the analytic surface;
* scenes/volumetric-caustic-small: scenes/volumetric-caustic with its light shrunk by `--light-scale` in each
  direction and its radiance raised by the inverse square, so that it emits the same power through a smaller
  opening (a sharper volumetric caustic).

Both are CC0 (LICENSE.txt beside each; glass-egg's scene.xml, SOURCE.md and LICENSE.txt are written by hand). Deterministic: rerunning gives the same bytes.

    python3 scripts/make_media_scenes.py [--rings 48] [--segments 96] [--light-scale 0.5]
"""
import argparse
import math
import os
import re

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")

SMALL_SOURCE = """# Volumetric caustic, smaller light

scenes/volumetric-caustic (Bitterli, CC0; see its SOURCE.md) with its light shrunk by {scale} in each direction
and its radiance multiplied by {boost:g}, so that it emits the same power through a smaller opening: a sharper
volumetric caustic below the glass sphere. Written by `python3 scripts/make_media_scenes.py --light-scale {scale}`.
"""

LICENSE = """CC0 1.0 Universal (public domain dedication)

{what} and its generator scripts/make_media_scenes.py were written for pathfarm and are dedicated to the public
domain: to the extent possible under law, the pathfarm authors have waived all copyright and related or
neighboring rights to them. See https://creativecommons.org/publicdomain/zero/1.0/.
"""


def egg_profile(t):
    """Radius and height of the egg at parameter t in [0, pi] (0: the narrow top): a prolate ellipse whose radius
    is skewed towards the bottom, rho = a sin t (1 - k cos t), y = b cos t."""
    a, b, k = 0.75, 1.0, 0.12
    return a * math.sin(t) * (1 - k * math.cos(t)), b * math.cos(t)


def egg_profile_derivative(t):
    a, b, k = 0.75, 1.0, 0.12
    drho = a * (math.cos(t) * (1 - k * math.cos(t)) + k * math.sin(t) ** 2)
    return drho, -b * math.sin(t)


def egg(rings, segments):
    """Vertices, normals and triangles (1-based, counter-clockwise seen from outside) of the egg mesh."""
    vertices, normals, triangles = [(0.0, 1.0, 0.0)], [(0.0, 1.0, 0.0)], []
    for i in range(1, rings):
        t = math.pi * i / rings
        rho, y = egg_profile(t)
        drho, dy = egg_profile_derivative(t)
        # The outward normal of the profile curve (drho, dy) in the (rho, y) plane is (-dy, drho) normalized.
        nl = math.hypot(dy, drho)
        nr, ny = -dy / nl, drho / nl
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            c, s = math.cos(phi), math.sin(phi)
            vertices.append((rho * c, y, rho * s))
            normals.append((nr * c, ny, nr * s))
    vertices.append((0.0, -1.0, 0.0))
    normals.append((0.0, -1.0, 0.0))
    bottom = len(vertices)

    def ring(i, j):
        return 2 + (i - 1) * segments + j % segments

    for j in range(segments):
        triangles.append((1, ring(1, j + 1), ring(1, j)))
        triangles.append((bottom, ring(rings - 1, j), ring(rings - 1, j + 1)))
    for i in range(1, rings - 1):
        for j in range(segments):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
            triangles.append((a, b, c))
            triangles.append((a, c, d))
    return vertices, normals, triangles


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)


def egg_scene(rings, segments):
    directory = os.path.join(ROOT, "scenes", "glass-egg")
    vertices, normals, triangles = egg(rings, segments)
    lines = ["# Egg of revolution for scenes/glass-egg, written by scripts/make_media_scenes.py (CC0)."]
    lines += ["v %.9f %.9f %.9f" % v for v in vertices]
    lines += ["vn %.9f %.9f %.9f" % n for n in normals]
    lines += ["f %d//%d %d//%d %d//%d" % (a, a, b, b, c, c) for a, b, c in triangles]
    write(os.path.join(directory, "models", "egg.obj"), "\n".join(lines) + "\n")


def small_light_scene(scale):
    source = os.path.join(ROOT, "scenes", "volumetric-caustic", "scene.xml")
    with open(source, encoding="utf-8") as f:
        xml = f.read()
    # The light is the last rectangle: its toWorld matrix's first three columns span the rectangle; scale the
    # first two (its extent) and keep the third (its normal) and the translation.
    light = re.search(r'(<matrix value=")([^"]*)("/>\s*</transform>\s*<ref id="Light" />)', xml)
    m = [float(x) for x in light.group(2).split()]
    for row in range(3):
        for col in range(2):
            m[4 * row + col] *= scale
    matrix = " ".join("%.9g" % x for x in m)
    xml = xml[: light.start(2)] + matrix + xml[light.end(2):]
    boost = 1 / (scale * scale)

    def brighter(match):
        return match.group(1) + ", ".join("%.9g" % (float(x) * boost) for x in match.group(2).split(",")) + '"'

    xml = re.sub(r'(<rgb name="radiance" value=")([^"]*)"', brighter, xml)
    xml = xml.replace("<!-- RECONSTRUCTED", "<!-- A smaller light (scripts/make_media_scenes.py). RECONSTRUCTED", 1)
    directory = os.path.join(ROOT, "scenes", "volumetric-caustic-small")
    write(os.path.join(directory, "scene.xml"), xml)
    write(os.path.join(directory, "SOURCE.md"), SMALL_SOURCE.format(scale=scale, boost=boost))
    write(os.path.join(directory, "LICENSE.txt"),
          LICENSE.format(what="This variant of Bitterli's CC0 'Volumetric Caustic' (scene.xml)"))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rings", type=int, default=48)
    parser.add_argument("--segments", type=int, default=96)
    parser.add_argument("--light-scale", type=float, default=0.5)
    args = parser.parse_args()
    egg_scene(args.rings, args.segments)
    small_light_scene(args.light_scale)


if __name__ == "__main__":
    main()
