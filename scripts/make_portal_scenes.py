#!/usr/bin/env python3
"""Writes the scenes of the portal perturbation (Otsu, Hanika & Dachsbacher, "Portal-Based Path Perturbation
for Metropolis Light Transport"; ALGORITHMS.md §7.2), each with its portal(s) and a CC0 licence file:

* scenes/portal-toy: the paper's three-plane toy (its sizes are not published; these are ours): an area light
  above an occluder with a small square hole above a diffuse reflector; the camera, between occluder and
  reflector, sees the reflector and the occluder's underside, lit only by light that came through the hole.
* scenes/portal-box: a closed box with a small opening in its roof under a constant environment, a sphere
  and a cube inside, seen from inside the box.
* scenes/cornell-box-portal: scenes/cornell-box with a portal just under its light.

Deterministic: rerunning gives the same bytes.

    python3 scripts/make_portal_scenes.py [--root DIR]
"""
import argparse
import os
import re

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- Written by scripts/make_portal_scenes.py (CC0, see LICENSE.txt). -->
<scene version="0.6.0">
\t<default name="res" value="128"/>
\t<integrator type="path">
\t\t<integer name="maxDepth" value="{max_depth}"/>
\t</integrator>
\t<sensor type="perspective">
\t\t<float name="fov" value="{fov}"/>
\t\t<transform name="toWorld">
\t\t\t<lookat origin="{origin}" target="{target}" up="0, 1, 0"/>
\t\t</transform>
\t\t<sampler type="independent">
\t\t\t<integer name="sampleCount" value="16"/>
\t\t</sampler>
\t\t<film type="hdrfilm">
\t\t\t<integer name="width" value="$res"/>
\t\t\t<integer name="height" value="$res"/>
\t\t\t<rfilter type="box"/>
\t\t</film>
\t</sensor>
\t<bsdf type="twosided" id="white">
\t\t<bsdf type="diffuse">
\t\t\t<rgb name="reflectance" value="0.7, 0.7, 0.7"/>
\t\t</bsdf>
\t</bsdf>
"""

LICENSE = """CC0 1.0 Universal (public domain dedication)

This scene ({name}/scene.xml) and its generator scripts/make_portal_scenes.py were written for pathfarm and are
dedicated to the public domain: to the extent possible under law, the pathfarm authors have waived all copyright
and related or neighboring rights to them. See https://creativecommons.org/publicdomain/zero/1.0/.
{extra}"""


def fmt(v):
    return ", ".join(("%g" % c) for c in v)


def horizontal(x0, x1, z0, z1, y, body, facing_up=True):
    """A rectangle [x0, x1] x [z0, z1] at height y (normal +y or -y)."""
    cx, cz, sx, sz = (x0 + x1) / 2, (z0 + z1) / 2, (x1 - x0) / 2, (z1 - z0) / 2
    # rotate x by -90 maps the rectangle's +z normal to +y (and its y axis to -z); +90 maps it to -y.
    angle = -90 if facing_up else 90
    return ("\t<shape type=\"rectangle\">\n\t\t<transform name=\"toWorld\">\n"
            "\t\t\t<scale x=\"%g\" y=\"%g\"/>\n\t\t\t<rotate x=\"1\" angle=\"%d\"/>\n"
            "\t\t\t<translate x=\"%g\" y=\"%g\" z=\"%g\"/>\n\t\t</transform>\n%s\t</shape>\n"
            % (sx, sz, angle, cx, y, cz, body))


def holed_plane(half, hx0, hx1, hz0, hz1, y, body):
    """The square [-half, half]^2 at height y without the hole [hx0, hx1] x [hz0, hz1], as four strips."""
    return (horizontal(-half, hx0, -half, half, y, body) + horizontal(hx1, half, -half, half, y, body) +
            horizontal(hx0, hx1, -half, hz0, y, body) + horizontal(hx0, hx1, hz1, half, y, body))


def portal(hx0, hx1, hz0, hz1, y):
    return horizontal(hx0, hx1, hz0, hz1, y, "\t\t<boolean name=\"portal\" value=\"true\"/>\n")


WHITE = "\t\t<ref id=\"white\"/>\n"


def toy():
    h = 0.25
    xml = HEADER.format(max_depth=9, fov=70, origin="3.5, 1.2, 3.5", target="0, 0.6, 0")
    xml += horizontal(-1, 1, -1, 1, 4, "\t\t<emitter type=\"area\">\n\t\t\t<rgb name=\"radiance\" value=\"20, 20, 20\"/>\n"
                      "\t\t</emitter>\n", facing_up=False)
    xml += "\t<!-- the occluder with its hole, and the portal in the hole -->\n"
    xml += holed_plane(4, -h, h, -h, h, 2, WHITE)
    xml += portal(-h, h, -h, h, 2)
    xml += "\t<!-- the reflector -->\n" + horizontal(-4, 4, -4, 4, 0, WHITE)
    return xml + "</scene>\n"


def box():
    x0, x1, z0, z1 = 0.2, 1.2, -0.2, 0.8
    xml = HEADER.format(max_depth=9, fov=75, origin="1.8, 1.6, 1.8", target="-0.6, 0.6, -0.6")
    xml += "\t<emitter type=\"constant\">\n\t\t<rgb name=\"radiance\" value=\"3, 3, 3\"/>\n\t</emitter>\n"
    xml += "\t<!-- floor, four walls, and the roof with its opening and the portal in it -->\n"
    xml += horizontal(-2, 2, -2, 2, 0, WHITE)
    walls = [("0, 1.5, -2", "0"), ("0, 1.5, 2", "180"), ("-2, 1.5, 0", "90"), ("2, 1.5, 0", "-90")]
    for centre, angle in walls:
        xml += ("\t<shape type=\"rectangle\">\n\t\t<transform name=\"toWorld\">\n\t\t\t<scale x=\"2\" y=\"1.5\"/>\n"
                "\t\t\t<rotate y=\"1\" angle=\"%s\"/>\n\t\t\t<translate value=\"%s\"/>\n\t\t</transform>\n%s\t</shape>\n"
                % (angle, centre, WHITE))
    xml += holed_plane(2, x0, x1, z0, z1, 3, WHITE)
    xml += portal(x0, x1, z0, z1, 3)
    xml += ("\t<shape type=\"sphere\">\n\t\t<point name=\"center\" x=\"-0.6\" y=\"0.6\" z=\"-0.4\"/>\n"
            "\t\t<float name=\"radius\" value=\"0.6\"/>\n\t\t<bsdf type=\"diffuse\">\n"
            "\t\t\t<rgb name=\"reflectance\" value=\"0.75, 0.3, 0.2\"/>\n\t\t</bsdf>\n\t</shape>\n")
    xml += ("\t<shape type=\"cube\">\n\t\t<transform name=\"toWorld\">\n\t\t\t<scale x=\"0.4\" y=\"0.4\" z=\"0.4\"/>\n"
            "\t\t\t<rotate y=\"1\" angle=\"30\"/>\n\t\t\t<translate x=\"0.8\" y=\"0.4\" z=\"-0.9\"/>\n\t\t</transform>\n"
            "\t\t<bsdf type=\"diffuse\">\n\t\t\t<rgb name=\"reflectance\" value=\"0.2, 0.4, 0.7\"/>\n\t\t</bsdf>\n\t</shape>\n")
    return xml + "</scene>\n"


def cornell(root):
    with open(os.path.join(root, "scenes", "cornell-box", "scene.xml"), encoding="utf-8") as f:
        xml = f.read()
    # The light spans x in [-0.24, 0.23], z in [-0.22, 0.16] at y = 1.98, facing down: the portal lies
    # 0.05 below it and a little larger.
    extra = ("\t<!-- the portal under the light (scripts/make_portal_scenes.py) -->\n" +
             portal(-0.3, 0.29, -0.28, 0.22, 1.93))
    return re.sub(r"</scene>\s*$", extra + "</scene>\n", xml)


SOURCE = """# {name}

Written by `python3 scripts/make_portal_scenes.py` for the portal perturbation (Otsu, Hanika & Dachsbacher,
"Portal-Based Path Perturbation for Metropolis Light Transport"; ALGORITHMS.md §7.2); CC0 (LICENSE.txt).
{what}
Render with the perturbation:

    pathfarm render scenes/{name}/scene.xml --integrator mlt -P portalPerturbation=true --time 60 -o out.exr
"""


def write(root, name, xml, what, extra=""):
    d = os.path.join(root, "scenes", name)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "scene.xml"), "w", encoding="utf-8") as f:
        f.write(xml)
    with open(os.path.join(d, "LICENSE.txt"), "w", encoding="utf-8") as f:
        f.write(LICENSE.format(name=name, extra=extra))
    with open(os.path.join(d, "SOURCE.md"), "w", encoding="utf-8") as f:
        f.write(SOURCE.format(name=name, what=what))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    root = parser.parse_args().root
    write(root, "portal-toy", toy(),
          "The paper's three-plane toy (its sizes are not published; these are ours): a 2 x 2 area light at height 4,\n"
          "an 8 x 8 occluder at height 2 with a 0.5 x 0.5 hole (the portal), a diffuse reflector at height 0; the\n"
          "camera, between occluder and reflector, sees only light that came through the hole. `$res` (default 128)\n"
          "sets the square resolution.\n")
    write(root, "portal-box", box(),
          "A closed 4 x 3 x 4 box with a 1 x 1 opening in its roof (the portal) under a constant environment, a\n"
          "sphere and a cube inside, seen from inside the box. `$res` (default 128) sets the square resolution.\n")
    write(root, "cornell-box-portal", cornell(root),
          "scenes/cornell-box with a portal 0.05 below its light, a little larger than the light. cornell-box's\n"
          "resolution is fixed (1024 x 1024) and it takes no `$res`.\n",
          "\nThe rest of the file is scenes/cornell-box/scene.xml, Benedikt Bitterli's Mitsuba version of the Cornell\n"
          "box (https://benedikt-bitterli.me/resources/), released under CC0 (scenes/cornell-box/LICENSE.txt).\n")


if __name__ == "__main__":
    main()
