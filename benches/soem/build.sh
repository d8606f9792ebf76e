#!/usr/bin/env bash
# Build benches/soem/soem_cycle.c against SOEM, for `ecdrive jitter`'s SOEM baseline.
#
#   benches/soem/build.sh [OUT_DIR]        (default: target/soem)
#
# SOEM's sources come from the pysoem 1.1.13 source distribution (SOEM 1.4), fetched by the
# package tool itself (`pip download --no-binary :all:`, from whatever index pip is configured
# with) and checked against its sha256; nothing of SOEM is kept in this repository. Never part
# of CI: the harness reports why SOEM is absent when the program is missing. On failure: one
# line on stderr, exit 1.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-$root/target/soem}"
sha="4be98d8531e492f2ee5d21f6ef51e51493a10ee1322ed22e909c91a8bcfff950"
no() { echo "soem_cycle not built: $*" >&2; exit 1; }

mkdir -p "$out" || no "cannot create $out"
bin="$out/soem_cycle"
if [ -x "$bin" ] && [ "$bin" -nt "$here/soem_cycle.c" ] && [ "$bin" -nt "$here/build.sh" ]; then
  echo "$bin"
  exit 0
fi
command -v gcc >/dev/null || no "gcc is not installed"
tarball="$out/pysoem-1.1.13.tar.gz"
if ! echo "$sha  $tarball" | sha256sum -c --status 2>/dev/null; then
  command -v python3 >/dev/null || no "python3 (for pip download) is not installed"
  rm -rf "$out/dl" && mkdir -p "$out/dl"
  python3 -m pip download --quiet --disable-pip-version-check --no-deps --no-binary :all: \
    --no-build-isolation -d "$out/dl" pysoem==1.1.13 >/dev/null 2>&1 ||
    python3 -m pip download --quiet --disable-pip-version-check --no-deps --no-binary :all: \
      -d "$out/dl" pysoem==1.1.13 >/dev/null 2>&1 ||
    no "pip download pysoem==1.1.13 (source distribution) failed"
  got="$out/dl/pysoem-1.1.13.tar.gz"
  [ -f "$got" ] || no "pip download gave no pysoem-1.1.13.tar.gz"
  echo "$sha  $got" | sha256sum -c --status || no "checksum mismatch for pysoem-1.1.13.tar.gz"
  mv "$got" "$tarball"
  rm -rf "$out/dl"
fi
src="$out/src"
rm -rf "$src" && mkdir -p "$src"
tar -xzf "$tarball" -C "$src" --strip-components=1 pysoem-1.1.13/soem pysoem-1.1.13/src/soem ||
  no "unpacking $tarball failed"
s="$src/soem"
# As pysoem builds it: EC_VER2 (own context, ecx_ functions) and its soem_config (timeouts).
gcc -O2 -std=gnu11 -Wall -DEC_VER2 -DUSE_SOEM_CONFIG_H -o "$bin.part" "$here/soem_cycle.c" \
  "$s"/soem/*.c "$s"/osal/linux/osal.c "$s"/oshw/linux/*.c "$src/src/soem/soem_config.c" \
  -I"$s/soem" -I"$s/osal" -I"$s/osal/linux" -I"$s/oshw/linux" -I"$src/src/soem" \
  -lpthread -lrt 2> "$out/build.log" || no "gcc failed (see $out/build.log)"
mv "$bin.part" "$bin"
echo "$bin"
