#!/usr/bin/env bash
# Renders a scene with Mitsuba 0.6 for about a given wall time, for side-by-side equal-time comparisons with
# pathfarm (issue 17, README "Tests and benchmarks"). Mitsuba is not a dependency of pathfarm: build it
# yourself (e.g. with ../shared/tools/build-mitsuba.sh) and pass the path of its `mitsuba` wrapper.
#
#   scripts/mitsuba-equal-time.sh MITSUBA SCENE.xml INTEGRATOR SECONDS RES OUT.exr [THREADS]
#
# Mitsuba 0.6 has no wall-time budget for its sampling integrators, so the budget becomes a sample count:
# probe renders (1 sample per pixel, then 4, 16, ... until a probe's extra samples take a tenth of the budget;
# for Mitsuba's mlt/pssmlt/erpt the sampler's sampleCount is mutations per pixel) separate the fixed start-up
# cost (loading, kd-tree, seeding) from the cost per sample, and the final render gets the count that fills
# SECONDS. The scene is rendered from a
# rewritten copy (integrator type, sampleCount, film width and height = RES, scene version 0.6.0, ldrfilm
# as hdrfilm; for mlt/pssmlt/erpt the sampler becomes `independent`, which Mitsuba's mlt and pssmlt require and
# which pathfarm's chains draw whatever the file asks; the scene's other files are linked), so the file itself
# is untouched and pathfarm renders it as it is. A render that writes no image (Mitsuba 0.6 exits with 0 when
# its render job throws) stops the script with its log. Prints the count and the measured wall time; compare with
#   bench_per_sample --res RES --time SECONDS --threads THREADS --integrators INTEGRATOR \
#       --reference REF.exr --image mitsuba=OUT.exr SCENE.xml
# Same work instead of equal time: with MITSUBA_COUNT=N set, the script renders exactly N samples (or mutations)
# per pixel, without probes (SECONDS unused), to time beside `pathfarm render SCENE.xml --spp N --threads
# THREADS`; run both under /usr/bin/time for their CPU seconds.
set -euo pipefail

if [ $# -lt 6 ]; then
    sed -n '2,20p' "$0"
    exit 2
fi
MITSUBA=$1 SCENE=$2 INTEGRATOR=$3 SECONDS_=$4 RES=$5 OUT=$6 THREADS=${7:-$(nproc)}
[ -x "$MITSUBA" ] || { echo "error: $MITSUBA is not an executable" >&2; exit 2; }
[ -f "$SCENE" ] || { echo "error: $SCENE: no such scene file" >&2; exit 2; }

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
SRC_DIR=$(cd "$(dirname "$SCENE")" && pwd)
for f in "$SRC_DIR"/*; do
    [ "$f" = "$SRC_DIR/$(basename "$SCENE")" ] || ln -s "$f" "$WORK/$(basename "$f")"
done

# The scene with INTEGRATOR, RES x RES and `count` samples per pixel, as $WORK/scene-COUNT.xml.
rewrite() {
    python3 - "$SCENE" "$WORK/scene-$1.xml" "$INTEGRATOR" "$RES" "$1" <<'PY'
import re, sys
src, dst, integrator, res, count = sys.argv[1:]
xml = open(src).read()
xml = re.sub(r'<integrator\s+type="[^"]*"', f'<integrator type="{integrator}"', xml, count=1)
xml = re.sub(r'(<integer\s+name="sampleCount"\s+value=")[^"]*"', rf'\g<1>{count}"', xml)
xml = re.sub(r'(<integer\s+name="(?:width|height)"\s+value=")[^"]*"', rf'\g<1>{res}"', xml)
# Mitsuba 0.6's mlt and pssmlt refuse any sampler but `independent` ("Metropolis light transport requires the
# independent sampler"); pathfarm's chains, erpt's included, draw independent numbers whatever the file asks, so
# both renderers then draw the same kind of numbers.
if integrator in ("mlt", "pssmlt", "erpt"):
    xml = re.sub(r'<sampler\s+type="[^"]*"', '<sampler type="independent"', xml, count=1)
# Mitsuba 0.6 refuses 0.5.0 files (its upgrade stylesheet only bumps the version), and an ldrfilm writes no
# EXR: the film becomes an hdrfilm without the ldrfilm's own properties.
xml = xml.replace('version="0.5.0"', 'version="0.6.0"').replace('type="ldrfilm"', 'type="hdrfilm"')
xml = re.sub(r'\s*<(?:string|float)\s+name="(?:fileFormat|gamma|exposure|tonemapMethod|key|burn)"[^>]*/>', '', xml)
open(dst, "w").write(xml)
PY
}

# Wall seconds of one Mitsuba render of $WORK/scene-COUNT.xml into FILE.
timed() {
    local start end
    start=$(date +%s.%N)
    rm -f "$2"
    "$MITSUBA" -q -p "$THREADS" -o "$2" "$WORK/scene-$1.xml" >"$WORK/log-$1" 2>&1 ||
        { cat "$WORK/log-$1" >&2; echo "error: mitsuba failed on $SCENE" >&2; exit 1; }
    # Mitsuba exits with 0 when the render job throws (e.g. an integrator that refuses the sampler); only the
    # missing image tells.
    if [ ! -s "$2" ]; then
        cat "$WORK/log-$1" >&2
        echo "error: mitsuba wrote no image for $SCENE ($INTEGRATOR)" >&2
        exit 1
    fi
    end=$(date +%s.%N)
    python3 -c "print($end - $start)"
}

# Same work (see the top): the given count, no probes.
if [ -n "${MITSUBA_COUNT:-}" ]; then
    rewrite "$MITSUBA_COUNT"
    T=$(timed "$MITSUBA_COUNT" "$OUT")
    echo "mitsuba $INTEGRATOR: $MITSUBA_COUNT samples per pixel at ${RES}x${RES} in $T s with $THREADS threads -> $OUT"
    exit 0
fi

rewrite 1
T1=$(timed 1 "$WORK/probe1.exr")
N=4
while :; do
    rewrite "$N"
    TN=$(timed "$N" "$WORK/probe$N.exr")
    python3 -c "import sys; sys.exit(0 if $TN - $T1 >= $SECONDS_ / 10 or $N >= 65536 else 1)" && break
    N=$((N * 4))
done
COUNT=$(python3 -c "
t1, tn, n, budget = $T1, $TN, $N, $SECONDS_
per = max((tn - t1) / (n - 1), 1e-6)
setup = max(t1 - per, 0)
print(max(1, int((budget - setup) / per)))")
rewrite "$COUNT"
T=$(timed "$COUNT" "$OUT")
echo "mitsuba $INTEGRATOR: $COUNT samples per pixel at ${RES}x${RES} in $T s with $THREADS threads (probes: 1 spp $T1 s, $N spp $TN s) -> $OUT"
