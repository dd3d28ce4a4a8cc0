#!/usr/bin/env python3
"""Writes scenes/sunsky/scene.xml: a small Z-up courtyard lit by Mitsuba's `sunsky` (a diffuse ground, a
glossy sphere, a diffuse box and a low wall casting a shadow), the scene that test_sunsky renders with `path`
and `bdpt`. The emitter keeps Mitsuba's default date, time and place (Tokyo, 10 July 2010, 15:00) and is
rotated to Z-up as the sunsky documentation suggests. Deterministic: rerunning gives the same bytes.

    python3 scripts/make_sunsky_scene.py [-o PATH]
"""
import argparse
import os

SCENE = """<?xml version="1.0" encoding="utf-8"?>
<!-- A courtyard lit by sunsky, Z-up (see SOURCE.md). Written by scripts/make_sunsky_scene.py. -->
<scene version="0.6.0">
	<default name="res" value="128"/>

	<integrator type="path">
		<integer name="maxDepth" value="{max_depth}"/>
	</integrator>

	<sensor type="perspective">
		<float name="fov" value="50"/>
		<transform name="toWorld">
			<lookat origin="6, -7, 3.5" target="0, 0, 0.6" up="0, 0, 1"/>
		</transform>
		<sampler type="independent">
			<integer name="sampleCount" value="16"/>
		</sampler>
		<film type="hdrfilm">
			<integer name="width" value="$res"/>
			<integer name="height" value="$res"/>
			<rfilter type="gaussian"/>
		</film>
	</sensor>

	<!-- Mitsuba's sky frame is Y-up; this rotation makes +Z the zenith (north is then +Y). -->
	<emitter type="sunsky">
		<float name="turbidity" value="{turbidity}"/>
		<rgb name="albedo" value="0.3, 0.25, 0.2"/>
		<integer name="resolution" value="256"/>
		<float name="sunRadiusScale" value="{sun_radius_scale}"/>
		<transform name="toWorld">
			<rotate x="1" angle="90"/>
		</transform>
	</emitter>

	<bsdf type="diffuse" id="ground">
		<rgb name="reflectance" value="0.45, 0.42, 0.38"/>
	</bsdf>
	<bsdf type="diffuse" id="brick">
		<rgb name="reflectance" value="0.6, 0.3, 0.2"/>
	</bsdf>
	<bsdf type="roughplastic" id="glossy">
		<float name="alpha" value="0.15"/>
		<rgb name="diffuseReflectance" value="0.2, 0.35, 0.6"/>
	</bsdf>

	<shape type="rectangle">
		<transform name="toWorld">
			<scale x="8" y="8" z="1"/>
		</transform>
		<ref id="ground"/>
	</shape>
	<shape type="cube">
		<transform name="toWorld">
			<scale x="0.7" y="0.7" z="0.7"/>
			<rotate z="1" angle="25"/>
			<translate x="-1.2" y="0.8" z="0.7"/>
		</transform>
		<ref id="brick"/>
	</shape>
	<shape type="cube">
		<transform name="toWorld">
			<scale x="3" y="0.15" z="0.9"/>
			<translate x="0.5" y="2.5" z="0.9"/>
		</transform>
		<ref id="brick"/>
	</shape>
	<shape type="sphere">
		<point name="center" x="1.3" y="-0.4" z="0.8"/>
		<float name="radius" value="0.8"/>
		<ref id="glossy"/>
	</shape>
</scene>
"""


def main():
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", default=os.path.join(here, "scenes", "sunsky", "scene.xml"))
    args = parser.parse_args()
    os.makedirs(os.path.dirname(args.o), exist_ok=True)
    with open(args.o, "w") as f:
        f.write(SCENE.format(max_depth=4, turbidity=3, sun_radius_scale=1))


if __name__ == "__main__":
    main()
