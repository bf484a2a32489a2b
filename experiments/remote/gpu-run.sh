#!/bin/bash
# One prepared GPU session, in the order that matters if time runs out: (1) the EGL path on the GPU
# (the report scene rendered shaded and as a node-visit heatmap, with GL_RENDERER in the JSON), (2)
# layouts-paper-gpu.toml (every layout with every kernel, the scenes past the L2 cache), (3)
# builders-gpu.toml, (4) layouts-gpu.toml with 8 s of rounds per group, (5) kernels-gpu.toml, (6) the
# report scene's 1080p frames over the builders with and without shared programs (docs/gpu.md, "Frame
# groups"). After (1), (1b) times the GPU builders (`build --json`, GL-timed over repeated builds) on
# scaling_1M and scaling_10M beside the CPU builders of this host. Each step has a time cap (0 skips it); a
# sweep stopped by its cap keeps its finished runs (resume with the same command). Results go to OUTDIR
# as a few files (PNG, JSON, one .tgz per sweep with its results.csv, results.json, findings.json and runs/);
# `bvhlab report DIR` makes the HTML where you unpack.
# Run from the repository root:
#   bash experiments/remote/gpu-run.sh BUNDLE OUTDIR [PAPER_S [BUILDERS_S [LAYOUTS_S [KERNELS_S [SHARING_S [GPUBUILD_S]]]]]]
# The default caps fit one 10-minute call: 90 s for step 1b, 270 s for step 2, 150 s for step 3, the
# older steps 4-6 skipped. GPUBUILD_MESHES (space-separated) replaces step 1b's two scenes.
# Environment: RENDER_S (step 1's cap, default 90; 0 skips it) and DYNAMIC_S (step 7, default 0 = skipped):
# experiments/configs/dynamic.toml, the update strategies over the bench animations with the GPU
# builders among the per-frame rebuilds. A second, shorter call runs what the first left out, e.g.
#   RENDER_S=0 DYNAMIC_S=200 bash experiments/remote/gpu-run.sh installed OUT2 0 0 0 0 0 0
# BUNDLE: a folder or .tar.xz from experiments/remote/bundle.py (or "installed": ./build/bvhlab as it is).
# datasets/cache must hold the meshes and worlds (bash datasets/fetch.sh, or unpack a copy of it).
set -u
bundle=$1; out=$2; paper_s=${3:-270}; builders_s=${4:-150}; layouts_s=${5:-0}; kernels_s=${6:-0}; sharing_s=${7:-0}
gpubuild_s=${8:-90}
render_s=${RENDER_S:-90}; dynamic_s=${DYNAMIC_S:-0}
t0=$(date +%s); step() { echo "[gpu-run t=$(( $(date +%s) - t0 ))s] $*"; }
mkdir -p "$out" /tmp/gpu-run
if [ "$bundle" = installed ]; then
  B=./build/bvhlab
else
  if [ -f "$bundle" ]; then mkdir -p /tmp/gpu-run/bundle && tar -C /tmp/gpu-run/bundle -xJf "$bundle" || exit 2
                            bundle=/tmp/gpu-run/bundle; fi
  B=$bundle/bvhlab; export LD_LIBRARY_PATH=$bundle/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
fi
# NVIDIA's EGL through glvnd: its vendor file, and the folder of libEGL_nvidia.so.0 (a driver mounted
# outside the loader's cache, as in containers).
vendor=$(find /usr/local/nvidia /usr/share/glvnd /etc/glvnd -path '*egl_vendor.d*' -name '*nvidia*.json' 2>/dev/null | head -1)
egl=$(find /usr/local/nvidia /usr/lib /usr/lib64 -name 'libEGL_nvidia.so.0' 2>/dev/null | head -1)
[ -n "$vendor" ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$vendor
[ -n "$egl" ] && export LD_LIBRARY_PATH=${LD_LIBRARY_PATH:+$LD_LIBRARY_PATH:}$(dirname "$egl")
step "binary $B; EGL vendor file '${vendor}', libEGL_nvidia '${egl}'"
nvidia-smi -L 2>/dev/null; echo "host: $(nproc) cores"

if [ "$render_s" -gt 0 ]; then
  step "1. the EGL path: the report scene, 1280x720"
  timeout "$render_s" "$B" render datasets/scenes/report.toml --backend egl --width 1280 --height 720 --frames 30 \
    --warmup 5 -o "$out/report_gpu.png" --json > "$out/render_report.json"; echo "rc=$?"
  head -c 600 "$out/render_report.json"; echo
  timeout 60 "$B" render datasets/scenes/report.toml --backend egl --width 1280 --height 720 --frames 5 \
    --view visits -o "$out/visits_gpu.png" --json > "$out/render_visits.json"; echo "rc=$?"
else
  step "1. the EGL path skipped"
fi

# 1b: one JSON line per build into gpu-builders.jsonl: the GPU builders with --gpu-builds 11 (median and
# interval of the GL-timed builds, phases, GL_RENDERER), the CPU builders three times each (build_ms is
# one wall-clock build). Every command gets what is left of the step's cap; past it the rest is skipped.
gpu_builders_step() {
  [ "$gpubuild_s" -gt 0 ] || { step "1b. GPU builders skipped"; return; }
  step "1b. GPU builders beside the CPU builders (at most $gpubuild_s s)"
  local end=$(( $(date +%s) + gpubuild_s )) mesh builder k left
  : > "$out/gpu-builders.jsonl"
  for mesh in ${GPUBUILD_MESHES:-datasets/scenes/bench/scaling_1M.toml datasets/scenes/bench/scaling_10M.toml}; do
    for builder in lbvh-gpu ploc-gpu plocpp-gpu hploc-gpu lbvh ploc sah-binned embree-low; do
      for k in 1 2 3; do
        case $builder in *-gpu) [ "$k" -gt 1 ] && continue ;; esac
        left=$(( end - $(date +%s) ))
        [ "$left" -gt 0 ] || { step "1b. cap reached: $mesh $builder and the rest skipped"; return; }
        BVHLAB_GPU_BUILD_BACKEND=${BVHLAB_GPU_BUILD_BACKEND:-egl} timeout "$left" "$B" build --mesh "$mesh" \
          --builder "$builder" --json --gpu-builds 11 >> "$out/gpu-builders.jsonl" 2>> "$out/gpu-builders.log" \
          || echo "$mesh $builder: rc=$?" | tee -a "$out/gpu-builders.log"
      done
    done
  done
  # Then the GPU builders' whole path to the compressed wide layout: the build packed into cwbvh, the
  # SAH wide collapse on the GPU included (docs/builders.md, "Packing on the GPU"), on the first scene;
  # last, so that the cap cuts these first.
  mesh=${GPUBUILD_MESHES:-datasets/scenes/bench/scaling_1M.toml}; mesh=${mesh%% *}
  for builder in hploc-gpu lbvh-gpu ploc-gpu plocpp-gpu; do
    left=$(( end - $(date +%s) ))
    [ "$left" -gt 0 ] || { step "1b. cap reached: cwbvh packs from $builder on skipped"; break; }
    BVHLAB_GPU_BUILD_BACKEND=${BVHLAB_GPU_BUILD_BACKEND:-egl} timeout "$left" "$B" build --mesh "$mesh" \
      --builder "$builder" --layout cwbvh --json --gpu-builds 11 >> "$out/gpu-builders.jsonl" 2>> "$out/gpu-builders.log" \
      || echo "$mesh $builder cwbvh: rc=$?" | tee -a "$out/gpu-builders.log"
  done
  step "1b. $(wc -l < "$out/gpu-builders.jsonl") builds in gpu-builders.jsonl"
}
gpu_builders_step

sweep() {  # name config seconds (0: skipped)
  [ "$3" -gt 0 ] || { step "$1 skipped"; return; }
  step "$1 (at most $3 s)"
  timeout "$3" "$B" run "$2" --out "/tmp/gpu-run/$1" --no-report > "/tmp/gpu-run/$1.log" 2>&1; echo "rc=$?"
  tail -3 "/tmp/gpu-run/$1.log"
  mkdir -p "/tmp/gpu-run/$1" && cp "/tmp/gpu-run/$1.log" "/tmp/gpu-run/$1/run.log"
  tar -C /tmp/gpu-run -czf "$out/$1.tgz" --exclude=images "$1"
  # results.json holds every run's per-round times and findings.json the paired intervals: keep both
  # beside results.csv (docs/gpu.md, "The committed results"), or the intervals cannot be re-derived.
  for f in results.csv results.json findings.json; do
    tar -tzf "$out/$1.tgz" "$1/$f" > /dev/null 2>&1 || echo "gpu-run: warning: $1.tgz has no $f"
  done
}
sweep layouts-paper-gpu experiments/configs/layouts-paper-gpu.toml "$paper_s"
sweep builders-gpu experiments/configs/builders-gpu.toml "$builders_s"
sed 's/^max_seconds = [0-9]*/max_seconds = 8/' experiments/configs/layouts-gpu.toml > /tmp/gpu-run/layouts-gpu.toml
sed -i 's|"\.\./\.\./datasets/|"'"$PWD"'/datasets/|' /tmp/gpu-run/layouts-gpu.toml
sweep layouts-gpu /tmp/gpu-run/layouts-gpu.toml "$layouts_s"
sweep kernels-gpu experiments/configs/kernels-gpu.toml "$kernels_s"
# 6: builders-gpu.toml's settings, only the report scene's frames, programs shared (the default) and not.
awk '/^\[\[sweep\]\]/{n++} n<1' experiments/configs/builders-gpu.toml > /tmp/gpu-run/shared.toml
printf '[[sweep]]\nname = "frames"\nscenes = { file = "%s/datasets/scenes/report.toml", name = "report" }\n' "$PWD" >> /tmp/gpu-run/shared.toml
sed 's/^\[measure\]/[measure]\nshare_programs = false/' /tmp/gpu-run/shared.toml > /tmp/gpu-run/unshared.toml
step "sharing (at most $sharing_s s each)"
mkdir -p /tmp/gpu-run/sharing
[ "$sharing_s" -gt 0 ] && for s in shared unshared; do
  timeout "$sharing_s" "$B" run /tmp/gpu-run/$s.toml --out /tmp/gpu-run/sharing/$s --no-report > /tmp/gpu-run/sharing/$s.log 2>&1
  echo "$s rc=$?"; grep 'sah-binned' /tmp/gpu-run/sharing/$s.log | tail -1
done
tar -C /tmp/gpu-run -czf "$out/sharing-gpu.tgz" --exclude=images sharing
# 7: the update strategies over the bench animations, the GPU builders rebuilding every frame beside
# the CPU builders of this host (docs/animation.md); on a GPU they rebuild the exploding mesh too
# (dynamic.toml leaves it out: on llvmpipe a ploc-gpu build takes ~0.8 s).
# hploc-gpu joins the GPU builders' per-frame rebuilds here (dynamic.toml's committed llvmpipe run has
# the other three).
sed -e 's|"\.\./\.\./datasets/|"'"$PWD"'/datasets/|' \
    -e 's|^builders = \["lbvh-gpu", "ploc-gpu", "plocpp-gpu"\]|builders = ["lbvh-gpu", "ploc-gpu", "plocpp-gpu", "hploc-gpu"]|' \
    experiments/configs/dynamic.toml > /tmp/gpu-run/dynamic-gpu.toml
printf '[[sweep]]\nname = "gpu-rebuild-explode"\nscenes = { file = "%s/datasets/scenes/bench/anim-explode.toml", name = "explode", clip_step = 1, clip_frames = 30 }\nbuilders = ["lbvh-gpu", "ploc-gpu", "plocpp-gpu", "hploc-gpu"]\nupdates = ["rebuild"]\n' "$PWD" >> /tmp/gpu-run/dynamic-gpu.toml
# The same rebuilds packed into cwbvh on the GPU (the wide collapse included in the update) and traced by
# the paper's kernel: the whole per-frame path of a real-time renderer with a compressed wide BVH.
printf '[[sweep]]\nname = "gpu-rebuild-explode-cwbvh"\nscenes = { file = "%s/datasets/scenes/bench/anim-explode.toml", name = "explode", clip_step = 1, clip_frames = 30 }\nbuilders = ["lbvh-gpu", "ploc-gpu", "plocpp-gpu", "hploc-gpu"]\nupdates = ["rebuild"]\nlayouts = ["cwbvh"]\nkernels = "cwbvh-groups"\n' "$PWD" >> /tmp/gpu-run/dynamic-gpu.toml
sweep dynamic-gpu /tmp/gpu-run/dynamic-gpu.toml "$dynamic_s"
step "done"; ls -la "$out"
