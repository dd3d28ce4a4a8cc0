#!/usr/bin/env python3
"""Writes scenes/ring-caustic-medium: scenes/ring-caustic (the SMS ring caustic) with its camera, light, gold ring
and floor inside a thin homogeneous fog with a forward-scattering Henyey-Greenstein phase function (g = 0.8), for
manifold exploration through media (ALGORITHMS.md §6.7): the ring's reflection of the small light becomes a
volumetric caustic in the fog (L S M E), whose paths chains of the manifold perturbation walk.

The fog fills an index-matched box (a cube without a BSDF, fog inside) that holds the whole ring-caustic scene, so
that no path of interest crosses its boundary (chains across index-matched boundaries are not supported); the
camera (a medium child of the sensor), the light, the ring and the floor name the fog on both sides. Its
optical depth from the camera to the ring is about 0.5, so that renders stay cheap.

    python3 scripts/make_ring_caustic_medium.py [--sigma-s 0.008] [--sigma-a 0.001] [--g 0.8]

Deterministic: rerunning gives the same bytes. The edits and this script are CC0; the ring scene keeps its
licence (scenes/ring-caustic/LICENSE.txt, copied as LICENSE-ring-caustic.txt).
"""
import argparse
import os
import shutil

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SOURCE_DIR = os.path.join(ROOT, "scenes", "ring-caustic")
TARGET_DIR = os.path.join(ROOT, "scenes", "ring-caustic-medium")

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- scenes/ring-caustic in a thin forward-scattering fog (homogeneous, Henyey-Greenstein g = {g}), written by
     scripts/make_ring_caustic_medium.py (see SOURCE.md): the ring's reflection of the light is also a volumetric
     caustic. The fog fills an index-matched box around the whole scene; camera, light, ring and floor lie in it. -->
"""

MEDIUM = """
\t<medium type="homogeneous" id="fog">
\t\t<rgb name="sigmaS" value="{s}, {s}, {s}"/>
\t\t<rgb name="sigmaA" value="{a}, {a}, {a}"/>
\t\t<phase type="hg">
\t\t\t<float name="g" value="{g}"/>
\t\t</phase>
\t</medium>

\t<!-- The fog's index-matched boundary (no BSDF): a box holding the camera, the light, the ring and the floor. -->
\t<shape type="cube">
\t\t<transform name="toWorld">
\t\t\t<scale x="110" y="31" z="110"/>
\t\t\t<translate x="0" y="30" z="0"/>
\t\t</transform>
\t\t<ref name="interior" id="fog"/>
\t</shape>
"""

FOG_REFS = '\t\t<ref name="interior" id="fog"/>\n\t\t<ref name="exterior" id="fog"/>\n'

SOURCE_MD = """# ring-caustic-medium - provenance

scenes/ring-caustic (the "Ring" caustic of Zeltner, Georgiev, Jakob 2020, see scenes/ring-caustic/SOURCE.md) in a
homogeneous fog: sigmaS {s}, sigmaA {a} per unit length (optical depth about 0.5 from the camera to the ring),
Henyey-Greenstein g = {g}, filling an index-matched box (110 x 31 x 110 half-extents about (0, 30, 0)) that holds
the camera, the light, the ring and the floor, which name the fog as their interior and exterior medium (the sensor as its
medium child). The integrator is volpath with maxDepth 8. Written by
`python3 scripts/make_ring_caustic_medium.py --sigma-s {s} --sigma-a {a} --g {g}`.

| file | source | note |
|---|---|---|
| scene.xml | derived from scenes/ring-caustic/scene.xml | the fog, its box, the medium references, volpath |
| LICENSE.txt | written here | CC0 for the edits and the generator |
| LICENSE-ring-caustic.txt | scenes/ring-caustic/LICENSE.txt | the ring scene's own licence |
"""

LICENSE = """CC0 1.0 Universal (public domain dedication)

The fog, its box and the medium references of scenes/ring-caustic-medium/scene.xml and their generator
scripts/make_ring_caustic_medium.py were written for pathfarm and are dedicated to the public domain: to the
extent possible under law, the pathfarm authors have waived all copyright and related or neighboring rights to
them. See https://creativecommons.org/publicdomain/zero/1.0/. The ring scene itself (scenes/ring-caustic) keeps its
own licence, copied here as LICENSE-ring-caustic.txt.
"""


def replace_once(text, old, new):
    if text.count(old) != 1:
        raise SystemExit("ring-caustic/scene.xml: expected one '%s'" % old)
    return text.replace(old, new)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sigma-s", type=float, default=0.008)
    parser.add_argument("--sigma-a", type=float, default=0.001)
    parser.add_argument("--g", type=float, default=0.8)
    args = parser.parse_args()
    values = {"s": "%g" % args.sigma_s, "a": "%g" % args.sigma_a, "g": "%g" % args.g}

    with open(os.path.join(SOURCE_DIR, "scene.xml")) as f:
        xml = f.read()
    # Drop the original's XML declaration and comment: the header replaces them.
    xml = xml[xml.index("<scene"):]
    xml = replace_once(xml, '<integrator type="path"/>',
                       '<integrator type="volpath">\n\t\t<integer name="maxDepth" value="8"/>\n\t</integrator>')
    xml = replace_once(xml, '\t<sensor type="perspective">\n', '\t<sensor type="perspective">\n\t\t<ref id="fog"/>\n')
    xml = replace_once(xml, '<scene version="0.6.0">\n', '<scene version="0.6.0">' + MEDIUM.format(**values))
    # Every shape of the original (light, ring, floor) lies in the fog, on both sides (a shape with a medium
    # reference sets the medium on each side).
    xml = xml.replace("\t\t<transform name=\"toWorld\">\n\t\t\t<scale x=\"0.1\"",
                      FOG_REFS + "\t\t<transform name=\"toWorld\">\n\t\t\t<scale x=\"0.1\"")
    xml = replace_once(xml, '\t<shape type="cylinder">\n', '\t<shape type="cylinder">\n' + FOG_REFS)
    xml = replace_once(xml, '\t\t<bsdf type="diffuse">\n\t\t\t<rgb name="reflectance" value="0.1, 0.1, 0.14"/>',
                       FOG_REFS + '\t\t<bsdf type="diffuse">\n'
                       '\t\t\t<rgb name="reflectance" value="0.1, 0.1, 0.14"/>')

    os.makedirs(TARGET_DIR, exist_ok=True)
    with open(os.path.join(TARGET_DIR, "scene.xml"), "w") as f:
        f.write(HEADER.format(**values) + xml)
    with open(os.path.join(TARGET_DIR, "SOURCE.md"), "w") as f:
        f.write(SOURCE_MD.format(**values))
    with open(os.path.join(TARGET_DIR, "LICENSE.txt"), "w") as f:
        f.write(LICENSE)
    shutil.copyfile(os.path.join(SOURCE_DIR, "LICENSE.txt"), os.path.join(TARGET_DIR, "LICENSE-ring-caustic.txt"))


if __name__ == "__main__":
    main()
