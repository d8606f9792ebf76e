#!/usr/bin/env bash
# Build benches/soem/soem_cycle.c against SOEM, for `ecdrive jitter`'s SOEM baseline.
#
#   benches/soem/build.sh [OUT_DIR]        (default: target/soem)
#
# SOEM's sources come from the pysoem 1.1.13 source distribution on PyPI (SOEM 1.4, checksum
# verified); nothing of SOEM is kept in this repository. Never part of CI: the harness reports
# why SOEM is absent when the program is missing. On failure: one line on stderr, exit 1.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-$root/target/soem}"
url="https://files.pythonhosted.org/packages/76/32/69116eb84c8f11a64561080a1401187a904afcaee4d7bd4e9717b0a21d4e/pysoem-1.1.13.tar.gz"
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
  command -v curl >/dev/null || no "curl is not installed"
  curl -fsSL --max-time 120 -o "$tarball.part" "$url" || no "downloading $url failed"
  echo "$sha  $tarball.part" | sha256sum -c --status || no "checksum mismatch for $url"
  mv "$tarball.part" "$tarball"
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
