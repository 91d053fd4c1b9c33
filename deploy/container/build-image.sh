#!/usr/bin/env bash
# Builds the csgtile container image with podman, on a local Debian 12 base image made with
# debootstrap (for machines that reach the Debian package mirror but no image registry).
#
# Usage: deploy/container/build-image.sh [IMAGE]      (as root; default localhost/csgtile:dev)
# Environment:
#   CSGTILE_IMAGE_SOURCE=REV   build from `git archive REV` instead of the working tree
#   CSGTILE_IMAGE_CONTEXT=DIR  build from a prepared source tree DIR instead
#   CSGTILE_BASE_IMAGE=NAME    base image (default localhost/debian:12, made here when missing)
#   CSGTILE_ROOTFS_CACHE=FILE  cached debootstrap tarball (default ~/.cache/csgtile/debian-12-minbase.tar)
#   DEBIAN_MIRROR=URL          (default http://deb.debian.org/debian)
#   BUILD_JOBS=N               parallel compile jobs in the image build (default 2)
# Prints the image's size and the build time at the end (and as JSON on the last line).
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
image="${1:-localhost/csgtile:dev}"
base="${CSGTILE_BASE_IMAGE:-localhost/debian:12}"
cache="${CSGTILE_ROOTFS_CACHE:-${HOME:-/root}/.cache/csgtile/debian-12-minbase.tar}"
mirror="${DEBIAN_MIRROR:-http://deb.debian.org/debian}"
jobs="${BUILD_JOBS:-2}"

# This machine's kernel runs cgroups in hybrid mode (crun refuses it) and refuses raising
# rlimits: every podman call takes these (../shared/notes/containers.md).
podman=(podman --runtime runc --cgroup-manager=cgroupfs)
limits=(--ulimit nofile=1024:1024 --ulimit nproc=1024:1024)

command -v podman >/dev/null || { echo "build-image: podman is not installed" >&2; exit 1; }
work="$(mktemp -d)"
cleanup() { rm -rf "$work"; }
trap cleanup EXIT

start=$(date +%s)
# 1. The base image: debootstrap once (cached as a tarball), then import.
if ! "${podman[@]}" image exists "$base"; then
  if [ "$base" != "localhost/debian:12" ]; then
    echo "build-image: base image $base does not exist (pull it, or leave CSGTILE_BASE_IMAGE unset)" >&2
    exit 1
  fi
  if [ ! -s "$cache" ]; then
    command -v debootstrap >/dev/null || { echo "build-image: debootstrap is not installed" >&2; exit 1; }
    [ "$(id -u)" -eq 0 ] || { echo "build-image: debootstrap needs root" >&2; exit 1; }
    echo "build-image: debootstrap bookworm (minbase) from $mirror"
    rootfs="$work/rootfs"
    debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 \
      || { tail -20 "$work/debootstrap.log" >&2; exit 1; }
    # As debian:12-slim: updates and security updates, no package caches.
    cat >"$rootfs/etc/apt/sources.list" <<SOURCES
deb $mirror bookworm main
deb $mirror bookworm-updates main
deb http://deb.debian.org/debian-security bookworm-security main
SOURCES
    rm -rf "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/lib/apt/lists/* "$rootfs"/tmp/*
    mkdir -p "$(dirname "$cache")"
    tar -C "$rootfs" --numeric-owner -cf "$cache.part" . && mv "$cache.part" "$cache"
  fi
  echo "build-image: importing $cache as $base"
  "${podman[@]}" import --change 'CMD ["/bin/bash"]' "$cache" "$base" >/dev/null
fi
base_done=$(date +%s)

# 2. The build context: the working tree (filtered by Dockerfile.dockerignore), or a commit.
context="${CSGTILE_IMAGE_CONTEXT:-$repo}"
if [ -n "${CSGTILE_IMAGE_SOURCE:-}" ]; then
  context="$work/context"
  mkdir -p "$context"
  git -C "$repo" archive "$CSGTILE_IMAGE_SOURCE" | tar -C "$context" -x
  echo "build-image: building from git $CSGTILE_IMAGE_SOURCE ($(git -C "$repo" rev-parse --short "$CSGTILE_IMAGE_SOURCE"))"
fi

# 3. The image. nice: compiling shares the machine's cores with other work.
nice -n 10 "${podman[@]}" build --format docker --network=host "${limits[@]}" \
  --build-arg BASE_IMAGE="$base" --build-arg BUILD_JOBS="$jobs" \
  --ignorefile "$repo/deploy/container/Dockerfile.dockerignore" \
  -f "$repo/deploy/container/Dockerfile" -t "$image" "$context"
end=$(date +%s)

size=$("${podman[@]}" image inspect --format '{{.Size}}' "$image")
echo "build-image: $image: $((size / 1000000)) MB, built in $((end - base_done)) s (base image $((base_done - start)) s)"
printf '{"image":"%s","size_bytes":%s,"build_seconds":%d,"base_seconds":%d}\n' \
  "$image" "$size" "$((end - base_done))" "$((base_done - start))"
