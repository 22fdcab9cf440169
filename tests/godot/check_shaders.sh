#!/usr/bin/env bash
# Compiles Godot 3 shaders (.shader, shader_type spatial) headless with Debian's godot3 under
# xvfb-run and prints one JSON line per shader (see project/check_shader.gd):
#   {"shader": "...", "mode": "spatial", "params": [...], "log": [...], "ok": true}
#
#   tests/godot/check_shaders.sh [--gles2] SHADER [SHADER ...]
#
# --gles2 checks them with Godot's GLES2 renderer (the default is GLES3): GLES2 rejects
# high-end built-ins such as texelFetch / textureSize at parse time. Exit status 0 when every
# shader is "ok" (neither Godot's shader compiler nor the GL driver printed an error), else 1.
# GODOT names the binary (default godot3).
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
driver=GLES3
if [ "${1:-}" = "--gles2" ]; then
  driver=GLES2
  shift
fi
if [ $# -lt 1 ]; then
  sed -n '2,12p' "$0" >&2
  exit 2
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cp -r "$here/project" "$work/project"
export HOME="$work/home"
export XDG_CONFIG_HOME="$HOME/.config" XDG_DATA_HOME="$HOME/.local/share" XDG_CACHE_HOME="$HOME/.cache"
mkdir -p "$XDG_CONFIG_HOME" "$XDG_DATA_HOME" "$XDG_CACHE_HOME"
export LANG=en_US.UTF-8
unset LC_ALL
shaders=""
for file in "$@"; do
  shaders="$shaders$(cd "$(dirname "$file")" && pwd)/$(basename "$file"):"
done
export FROND_GODOT_SHADERS="$shaders"
export FROND_GODOT_LOG="$work/godot.log"
set +e
timeout 300 xvfb-run -a -s "-screen 0 1024x768x24" "${GODOT:-godot3}" --audio-driver Dummy \
  --video-driver "$driver" --path "$work/project" -s res://check_shader.gd \
  > "$work/stdout" 2> "$FROND_GODOT_LOG"
status=$?
set -e
grep '^{"' "$work/stdout" || true
lines=$(grep -c '^{"' "$work/stdout" || true)
if [ "$status" -ne 0 ] || [ "$lines" -ne $# ]; then
  echo "check_shaders.sh: Godot printed $lines of $# JSON lines (exit status $status)" >&2
  tail -n 20 "$FROND_GODOT_LOG" >&2
  exit 1
fi
if grep '^{"' "$work/stdout" | grep -q '"ok":false'; then
  exit 1
fi
