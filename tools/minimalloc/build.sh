#!/bin/bash
# Builds MiniMalloc's C++ solver with a minimal driver (no absl flags/log needed), for the
# timing comparison in docs/memory.md. Needs g++, pkg-config and Debian's libabsl-dev
# (20220623: no absl/log, so DLOG/LOG become no-ops), and a checkout of google/minimalloc.
#   tools/minimalloc/build.sh /path/to/minimalloc OUT_BINARY
set -euo pipefail
src=$1; out=$2
here=$(cd "$(dirname "$0")" && pwd)
stub=$(mktemp -d)
mkdir -p "$stub/absl/log"
cat > "$stub/absl/log/log.h" <<'H'
#pragma once
struct NullStream_ { template <class T> NullStream_& operator<<(const T&) { return *this; } };
#define DLOG(x) if (true) {} else NullStream_()
#define LOG(x) if (true) {} else NullStream_()
H
g++ -O2 -std=c++20 -DNDEBUG -I"$stub" -I"$src/src" "$src"/src/{solver,sweeper,minimalloc,validator}.cc \
  "$here/minimalloc_driver.cc" -o "$out" \
  $(pkg-config --libs absl_statusor absl_strings absl_time absl_flat_hash_set absl_btree)
rm -rf "$stub"
