#!/bin/bash
# Packs mppi-bench, mppi-tests and mppi-sim with the shared libraries they load (except the C
# and C++ runtimes, which the target's newer glibc / libstdc++ provide) into one archive, to run
# the Vulkan backend on a GPU machine that has no Debian packages and no network.
#   bash scripts/device_bundle.sh [build-dir] [out.tar.xz]
# On the target: tar xJf out.tar.xz -C /tmp; export LD_LIBRARY_PATH=/tmp/gpub/lib;
#   PLPLOT_DRV_DIR=/tmp/gpub/drivers PLPLOT_LIB=/tmp/gpub/plplot-data for the PNG figures.
# OpenCV's image codecs pull in GDAL and its ~100 MB of dependencies; the programs never read a
# GDAL format, so libgdal is replaced by a stub that defines the symbols OpenCV binds to
# (and aborts if one were called).
set -euo pipefail
build=${1:-build}
out=${2:-gpub.tar.xz}
work=$(mktemp -d)
dest=$work/gpub
mkdir -p "$dest/lib" "$dest/drivers"
system_runtime='/libc\.so|/libm\.so|/libstdc\+\+|/libgcc_s|ld-linux|libpthread|libdl\.so|librt\.so'

imgcodecs=$(ldd "$build/bin/mppi-bench" | awk '/libopencv_imgcodecs/ {print $3}')
gdal=$(ldd "$build/bin/mppi-bench" | awk '/libgdal/ {print $3}')
if [ -n "$gdal" ]; then
  comm -12 <(nm -D --defined-only "$gdal" | awk '{print $3}' | sed 's/@.*//' | sort -u) \
           <(nm -D --undefined-only "$imgcodecs" | awk '{print $2}' | sed 's/@.*//' | sort -u) |
    { echo '#include <stdlib.h>'; while read -r s; do echo "void $s(void) { abort(); }"; done; } > "$work/gdal_stub.c"
  gcc -shared -fPIC -Wl,-soname,"$(basename "$gdal")" -o "$dest/lib/$(basename "$gdal")" "$work/gdal_stub.c"
fi
plplot_drivers=$(ls -d /usr/lib/x86_64-linux-gnu/plplot*/drivers | head -1)
cp "$plplot_drivers"/cairo.* "$dest/drivers/"
cp -r "$(ls -d /usr/share/plplot* | head -1)" "$dest/plplot-data"
for f in "$build/bin/mppi-bench" "$build/bin/mppi-tests" "$build/bin/mppi-sim" "$dest/drivers/cairo.so"; do
  LD_LIBRARY_PATH=$dest/lib ldd "$f" | awk '$3 ~ /^\// {print $3}'
done | sort -u | grep -v -E "$system_runtime|^$dest" | xargs -I{} cp -L {} "$dest/lib/"
cp -L "$(ldconfig -p | awk '/libvulkan.so.1 / {print $NF; exit}')" "$dest/lib/"
cp "$build/bin/mppi-bench" "$build/bin/mppi-tests" "$build/bin/mppi-sim" "$dest/"
tar cJf "$out" -C "$work" gpub
rm -rf "$work"
echo "$out: $(du -h "$out" | cut -f1)"
