#!/usr/bin/env bash
# Packs a built `vxr` with the shared libraries it needs (all but glibc and
# the C++ runtime, which a newer host provides) so the GPU benchmarks can run
# on a machine without our Debian packages, e.g. an Ubuntu GPU box:
#
#   tools/make-gpu-bundle.sh build/release build/gpu-bundle
#   # on the GPU machine, from the repo root:
#   build/gpu-bundle/vxr bench lod --out out/bench-gpu
#
# The wrapper also points the Vulkan loader at NVIDIA's EGL library when the
# host has one: in headless containers libGLX_nvidia (the stock ICD) cannot
# create an instance without an X server, libEGL_nvidia can.
set -euo pipefail
build=${1:-build/release}
out=${2:-build/gpu-bundle}
here=$(cd "$(dirname "$0")/.." && pwd)

rm -rf "$out"
mkdir -p "$out/bin" "$out/lib" "$out/testdata/tiff"
cp "$build/tools/vxr" "$out/bin/"
ldd "$build/tools/vxr" | awk '$3 ~ /^\// {print $3}' | while read -r lib; do
  case $(basename "$lib") in
    libc.so*|libm.so*|libdl.so*|libpthread.so*|librt.so*|libstdc++*|libgcc_s*) ;;
    *) cp -L "$lib" "$out/lib/" ;;
  esac
done
# bench accuracy's second dataset.
cp "$here/../shared/testdata/tiff/mri-stack-calibrated.tif" "$out/testdata/tiff/"

cat > "$out/vxr" <<'EOF'
#!/usr/bin/env bash
dir=$(cd "$(dirname "$0")" && pwd)
export LD_LIBRARY_PATH="$dir/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
for egl in /usr/local/nvidia/lib64/libEGL_nvidia.so.0 /usr/lib/x86_64-linux-gnu/libEGL_nvidia.so.0; do
  if [ -z "${VK_ICD_FILENAMES:-}" ] && [ -e "$egl" ]; then
    icd=$(mktemp --suffix=.json)
    printf '{"file_format_version":"1.0.1","ICD":{"library_path":"%s","api_version":"1.3.0"}}\n' "$egl" > "$icd"
    export VK_ICD_FILENAMES=$icd
  fi
done
exec "$dir/bin/vxr" "$@"
EOF
chmod +x "$out/vxr"
echo "$out: $(du -sh "$out" | cut -f1) ($(ls "$out/lib" | wc -l) libraries); run $out/vxr"
