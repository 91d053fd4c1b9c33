#!/bin/sh
# The container image (deploy/container): `csgtile --version`, non-root user, and the README's
# demo run with the root file system read-only and the output on a volume, as Kubernetes runs
# it; the health check when the image's csgtile has the metrics endpoint.
# Runs when podman works and the image exists; CSGTILE_CONTAINER_TEST=1 builds the image first
# (deploy/container/build-image.sh: minutes, so not by default). Exit 77 = skipped.
# Usage: container_image.sh REPO_DIR     (image: $CSGTILE_IMAGE, default localhost/csgtile:dev)
set -eu
repo="$1"
image="${CSGTILE_IMAGE:-localhost/csgtile:dev}"
podman_cmd="podman --runtime runc --cgroup-manager=cgroupfs"
limits="--ulimit nofile=1024:1024 --ulimit nproc=1024:1024"

command -v podman >/dev/null || { echo "SKIP: podman is not installed"; exit 77; }
[ "$(id -u)" -eq 0 ] || { echo "SKIP: needs root (podman with runc and cgroupfs as in ../shared/notes/containers.md)"; exit 77; }
$podman_cmd info >/dev/null 2>&1 || { echo "SKIP: podman does not work here ($podman_cmd info fails)"; exit 77; }
if [ "${CSGTILE_CONTAINER_TEST:-0}" = 1 ]; then
  "$repo/deploy/container/build-image.sh" "$image"
elif ! $podman_cmd image exists "$image"; then
  echo "SKIP: no image $image; build it with deploy/container/build-image.sh, or run this test with CSGTILE_CONTAINER_TEST=1"
  exit 77
fi

# --no-healthcheck: one-shot runs; podman would try to schedule health checks with systemd.
run() { $podman_cmd run --rm --no-healthcheck $limits "$@"; }

version="$(run "$image" --version)"
echo "$version" | grep -Eq '^csgtile [0-9]+\.[0-9]+\.[0-9]+' || { echo "FAIL: --version printed: $version"; exit 1; }
echo "ok: $version"

uid="$(run --entrypoint id "$image" -u)"
[ "$uid" = 10001 ] || { echo "FAIL: the image runs as uid $uid, expected the non-root 10001"; exit 1; }
echo "ok: runs as uid $uid"

out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
chown 10001:10001 "$out"
summary="$(run --read-only --tmpfs /tmp -v "$out:/data" -e CSGTILE_RUN__OUTPUT=/data/out \
             "$image" run config/examples/demo.yaml --json)"
echo "$summary" | grep -q '"done":3' && echo "$summary" | grep -q '"dead":0' \
  || { echo "FAIL: demo summary: $summary"; exit 1; }
[ -s "$out/out/runs/demo/manifest.json" ] && [ -s "$out/out/runs/demo/index.gpkg" ] \
  || { echo "FAIL: the demo published no manifest or index under the volume"; ls -R "$out"; exit 1; }
echo "ok: demo in the container (read-only root, output on a volume): $summary"

# The modules the image installs beside the binary (csgtile/kernel/module.h) load: footprints
# are read by the GDAL one (a run whose footprint layer is misnamed stops at its check, exit 78,
# with the layers GDAL lists), and the assembly culls with the OpenVDB one (a ball in a ring's
# hole: the one candidate pair culled, no "voxel culling skipped" problem).
printf '%s\n' '{"type":"FeatureCollection","features":[{"type":"Feature","properties":{},' \
  '"geometry":{"type":"Polygon","coordinates":[[[0,0],[1,0],[1,1],[0,0]]]}}]}' > "$out/fp.geojson"
printf 'run:\n  name: fp\n  inputs:\n    - /data/none.las\n  output: /data/fp\ncity:\n  footprints: /data/fp.geojson\n  footprints_layer: nope\n' \
  > "$out/fp.yaml"
printf '%s\n' '{"name":"ring","primitives":[{"id":"ring","type":"torus","R":5.0,"r":1.0},' \
  '{"id":"ball","type":"sphere","r":2.0}]}' > "$out/ring.json"
chown 10001:10001 "$out/fp.geojson" "$out/fp.yaml" "$out/ring.json"
rc=0
checked="$(run --read-only --tmpfs /tmp -v "$out:/data" "$image" run /data/fp.yaml 2>&1)" || rc=$?
[ "$rc" = 78 ] && echo "$checked" | grep -q "no layer 'nope'; its layers: fp" \
  || { echo "FAIL: footprints through the GDAL module (exit $rc): $checked"; exit 1; }
echo "ok: footprints read through the image's GDAL module"
culled="$(run --read-only --tmpfs /tmp -v "$out:/data" "$image" assemble /data/ring.json \
            --out /data/ring --json)" || { echo "FAIL: assemble in the image: $culled"; exit 1; }
echo "$culled" | grep -q '"culled_pairs":1' && ! echo "$culled" | grep -q 'voxel culling skipped' \
  || { echo "FAIL: the image's assembly did not cull with the OpenVDB module: $culled"; exit 1; }
echo "ok: the assembly culls with the image's OpenVDB module"

# The health check needs the worker's endpoint (metrics.listen); older binaries have none.
schema="$(run "$image" config schema)"
if echo "$schema" | grep -q '"metrics"'; then
  # `podman healthcheck run` runs the image's HEALTHCHECK once (podman cannot schedule it
  # without systemd, and says so on stderr).
  name="csgtile-health-$$"
  $podman_cmd run -d --name "$name" $limits -e CSGTILE_METRICS__LISTEN=127.0.0.1:9464 \
    -e CSGTILE_RUN__OUTPUT=/tmp/out "$image" worker config/examples/demo.yaml >/dev/null 2>&1
  status=1
  for _ in 1 2 3 4 5 6 7 8 9 10; do
    sleep 1
    if $podman_cmd healthcheck run "$name" >/dev/null 2>&1; then status=0; break; fi
  done
  # Without the endpoint the same check must fail: it really probes /healthz.
  wrong=0
  $podman_cmd exec -e CSGTILE_HEALTH_PORT=9465 "$name" /usr/local/lib/csgtile/healthcheck \
    >/dev/null 2>&1 || wrong=1
  $podman_cmd rm -f -t 30 "$name" >/dev/null 2>&1
  [ "$status" = 0 ] || { echo "FAIL: the health check never passed for a running worker"; exit 1; }
  [ "$wrong" = 1 ] || { echo "FAIL: the health check passed with nothing listening"; exit 1; }
  echo "ok: health check passes for a running worker (and fails on a port with no endpoint)"
else
  echo "note: this image's csgtile has no metrics endpoint; health check not exercised"
fi
echo "container image checks passed"
