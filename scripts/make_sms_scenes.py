#!/usr/bin/env python3
"""Writes the specular manifold sampling scenes (CC0, made for pathfarm; ALGORITHMS.md §7.1, issue 15):

* scenes/sphere-caustic: a glass sphere on a diffuse plane under a small area light (the caustic under the
  sphere is L S S D: two refractions), and a mirror sphere beside it (an L S D caustic, one reflection).
* scenes/pool-caustic: a diffuse pool floor under a flat water surface (eta 1.33), lit by a small area light
  above the water and seen from above through it (L S D S E: the floor's light comes through one refraction).

Deterministic: rerunning gives the same bytes.

    python3 scripts/make_sms_scenes.py [--root DIR]
"""
import argparse
import os

LICENSE = """CC0 1.0 Universal (public domain dedication)

The {name} scene (scene.xml) and its generator scripts/make_sms_scenes.py were written for pathfarm and are
dedicated to the public domain: to the extent possible under law, the pathfarm authors have waived all
copyright and related or neighboring rights to them. See https://creativecommons.org/publicdomain/zero/1.0/.
"""

SENSOR = """	<sensor type="perspective">
		<float name="fov" value="{fov}"/>
		<transform name="toWorld">
			<lookat origin="{origin}" target="{target}" up="0, 1, 0"/>
		</transform>
		<sampler type="independent">
			<integer name="sampleCount" value="64"/>
		</sampler>
		<film type="hdrfilm">
			<integer name="width" value="256"/>
			<integer name="height" value="256"/>
			<rfilter type="box"/>
		</film>
	</sensor>
"""

LIGHT = """	<shape type="rectangle">
		<transform name="toWorld">
			<scale x="{size}" y="{size}" z="{size}"/>
			<rotate x="1" y="0" z="0" angle="90"/>
			<translate x="{x}" y="{y}" z="{z}"/>
		</transform>
		<emitter type="area">
			<spectrum name="radiance" value="{radiance}"/>
		</emitter>
	</shape>
"""

FLOOR = """	<shape type="rectangle">
		<bsdf type="diffuse">
			<rgb name="reflectance" value="{rgb}"/>
		</bsdf>
		<transform name="toWorld">
			<scale x="{size}" y="{size}" z="{size}"/>
			<rotate x="1" y="0" z="0" angle="-90"/>
			<translate y="{y}"/>
		</transform>
	</shape>
"""

# The start of both scenes: the path tracer with the depth that sms needs, the camera and the light.
HEAD = """<scene version="0.6.0">
	<integrator type="path">
		<integer name="maxDepth" value="8"/>
	</integrator>

{sensor}
{light}"""

SPHERE_CAUSTIC = """<?xml version="1.0" encoding="utf-8"?>
<!-- SPHERE-CAUSTIC (CC0, scripts/make_sms_scenes.py): a glass sphere (bk7) and a mirror sphere on a diffuse
     plane under a small area light. The mirror sphere's caustic is L S D (one-bounce SMS); the glass sphere's is
     L S S D (two refractions: left to the path tracer by one-bounce sms). -->
{head}	<shape type="sphere">
		<point name="center" x="-1.2" y="1" z="0"/>
		<float name="radius" value="1"/>
		<bsdf type="dielectric"/>
	</shape>

	<shape type="sphere">
		<point name="center" x="1.3" y="0.8" z="0.4"/>
		<float name="radius" value="0.8"/>
		<bsdf type="conductor">
			<string name="material" value="none"/>
		</bsdf>
	</shape>

{floor}</scene>
"""

POOL_CAUSTIC = """<?xml version="1.0" encoding="utf-8"?>
<!-- POOL-CAUSTIC (CC0, scripts/make_sms_scenes.py): a diffuse pool floor one unit under a flat water surface
     (intIOR 1.33), a small area light above the water, the camera above looking down through it. The floor's
     light arrives through one refraction (L S D), and the camera sees it through another (... D S E). -->
{head}	<shape type="rectangle">
		<bsdf type="dielectric">
			<float name="intIOR" value="1.33"/>
			<float name="extIOR" value="1"/>
		</bsdf>
		<transform name="toWorld">
			<scale x="4" y="4" z="4"/>
			<rotate x="1" y="0" z="0" angle="-90"/>
		</transform>
	</shape>

{floor}</scene>
"""

SOURCE = """# {title}

Made for pathfarm (CC0, LICENSE.txt) by `python3 scripts/make_sms_scenes.py`, for specular manifold sampling
(Zeltner, Georgiev, Jakob 2020; issue 15): {what} Sizes, colours and positions are ours. Rerunning the script
reproduces the files byte for byte.
"""


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    root = parser.parse_args().root

    sphere = SPHERE_CAUSTIC.format(
        head=HEAD.format(sensor=SENSOR.format(fov=35, origin="0, 6, 9", target="0, 0.6, 0"),
                         light=LIGHT.format(size=0.15, x=0.5, y=5, z=-1, radiance=3000)),
        floor=FLOOR.format(rgb="0.6, 0.6, 0.6", size=10, y=0),
    )
    write(os.path.join(root, "scenes/sphere-caustic/scene.xml"), sphere)
    write(os.path.join(root, "scenes/sphere-caustic/LICENSE.txt"), LICENSE.format(name="SPHERE-CAUSTIC"))
    write(os.path.join(root, "scenes/sphere-caustic/SOURCE.md"),
          SOURCE.format(title="SPHERE-CAUSTIC", what="a glass sphere on a diffuse plane under a small light "
                        "(the set-up of the paper's refractive sphere, Fig. 8), with a mirror sphere beside it."))

    pool = POOL_CAUSTIC.format(
        head=HEAD.format(sensor=SENSOR.format(fov=40, origin="0, 5, 4", target="0, -1, 0"),
                         light=LIGHT.format(size=0.1, x=-1, y=2, z=-1, radiance=1600)),
        floor=FLOOR.format(rgb="0.3, 0.6, 0.7", size=4, y=-1),
    )
    write(os.path.join(root, "scenes/pool-caustic/scene.xml"), pool)
    write(os.path.join(root, "scenes/pool-caustic/LICENSE.txt"), LICENSE.format(name="POOL-CAUSTIC"))
    write(os.path.join(root, "scenes/pool-caustic/SOURCE.md"),
          SOURCE.format(title="POOL-CAUSTIC", what="a caustic seen through a flat water surface (after the "
                        "paper's swimming pool, Fig. 14, with a flat surface)."))


if __name__ == "__main__":
    main()
