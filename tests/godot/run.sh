#!/usr/bin/env bash
# Imports glTF files into Godot 3 (Debian's godot3, 3.2.x) with its editor importer, loads each
# as a game would, prints one JSON line per file with what Godot made of it and renders it to
# PNG; headless, under xvfb-run.
#
#   tests/godot/run.sh OUT_DIR FILE.glb[=REFERENCE.glb] [...]
#
# With `=REFERENCE.glb`, frond frames and renders REFERENCE instead of FILE (a VAT LOD against
# the same LOD written skinned: frond does not play VAT). A FILE with a VAT sidecar beside it
# (`<stem>_vat.json`, frond's naming) has its textures imported too, and inspect.gd plays its
# `_vat` mesh with the shipped Godot 3 VAT material (export/shaders/frond_vat_rigid_godot3.shader)
# at each clip time.
#
# Environment:
#   FROND=path/to/frond       also frame Godot's camera on `frond inspect`'s rest-pose bounds and
#                             write frond's own render of the same view (`frond render`) beside it
#   FROND_GODOT_TIMES=0       clip times of the frames (s), space-separated; the clip paused there
#   FROND_GODOT_CLIP=         clip to pose (default: Godot's first animation / frond's first clip)
#   FROND_GODOT_SIZE=512x512  image size
#   FROND_GODOT_AZIMUTH=0, FROND_GODOT_ELEVATION=10   camera, as `frond render`'s
#   GODOT=godot3              the Godot 3 binary
#
# Writes into OUT_DIR:
#   project/                  the Godot project: tests/godot/project plus the models, each in its
#                             own folder under models/ (Godot extracts a model's materials next to
#                             it by material name: one folder would share them between LODs)
#   <stem>.tT.godot.png       Godot's frame at time T (as written in FROND_GODOT_TIMES), as
#                             imported; background magenta (1, 0, 1)
#   <stem>.tT.godot_frondsampling.png   the same, textures sampled as frond render samples them
#                             (no mipmaps, foliage textures clamped; see project/inspect.gd)
#   <stem>.tT.frond.png       frond's frame (with FROND); transparent background
#   results.jsonl             the JSON lines, also printed on stdout
#   godot_import.log, godot_inspect.log   what Godot printed
# <stem> is the file's name without its extension, with "_<position>" appended when an earlier
# argument had the same name. Exit status: 0 when every file produced a JSON line, else 1.
set -euo pipefail

if [ $# -lt 2 ]; then
  sed -n '2,31p' "$0" >&2
  exit 2
fi
here="$(cd "$(dirname "$0")" && pwd)"
out="$1"
shift
mkdir -p "$out"
out="$(cd "$out" && pwd)"
godot="${GODOT:-godot3}"
times="${FROND_GODOT_TIMES:-0}"
clip="${FROND_GODOT_CLIP:-}"
size="${FROND_GODOT_SIZE:-512x512}"
export FROND_GODOT_AZIMUTH="${FROND_GODOT_AZIMUTH:-0}"
export FROND_GODOT_ELEVATION="${FROND_GODOT_ELEVATION:-10}"

proj="$out/project"
rm -rf "$proj"
cp -r "$here/project" "$proj"
cp "$here/../../export/shaders/frond_vat_rigid_godot3.shader" "$proj/"
# Godot's editor settings, caches and user data: kept out of the real home.
export HOME="$out/home"
export XDG_CONFIG_HOME="$HOME/.config" XDG_DATA_HOME="$HOME/.local/share" XDG_CACHE_HOME="$HOME/.cache"
mkdir -p "$XDG_CONFIG_HOME" "$XDG_DATA_HOME" "$XDG_CACHE_HOME"
if [ -z "${XDG_RUNTIME_DIR:-}" ] || [ ! -d "${XDG_RUNTIME_DIR}" ]; then
  export XDG_RUNTIME_DIR="$HOME/runtime"
  mkdir -p "$XDG_RUNTIME_DIR"
  chmod 700 "$XDG_RUNTIME_DIR"
fi
# Godot 3.2 reads the locale from LANG and rejects "C" with an error line.
export LANG=en_US.UTF-8
unset LC_ALL

: > "$proj/frond_import.txt"
: > "$proj/frond_inspect.txt"
declare -A seen=()
index=0
for arg in "$@"; do
  index=$((index + 1))
  file="${arg%%=*}"
  reference="$file"
  [ "$arg" = "$file" ] || reference="${arg#*=}"
  src="$(cd "$(dirname "$file")" && pwd)/$(basename "$file")"
  ref="$(cd "$(dirname "$reference")" && pwd)/$(basename "$reference")"
  name="$(basename "$file")"
  stem="${name%.*}"
  # Two inputs with one name (two chains of one tree) get the second's position appended.
  [ -z "${seen[$stem]:-}" ] || stem="${stem}_$index"
  seen[$stem]=1
  res="res://models/$stem/$name"
  # A VAT LOD's textures, imported beside it (their names from the sidecar).
  vat="${src%.*}_vat.json"
  if [ -f "$vat" ]; then
    for texture in $(sed -n 's/^ *"\(position\|rotation\|pivot\)": "\(.*\)",\{0,1\}$/\2/p' "$vat"); do
      printf '%s\t%s\n' "$(dirname "$src")/$texture" "res://models/$stem/$texture" >> "$proj/frond_import.txt"
    done
  else
    vat=""
  fi
  bounds=""
  if [ -n "${FROND:-}" ]; then
    # "  bounds: [x, y, z] .. [x, y, z]" -> "x,y,z,x,y,z"
    bounds="$("$FROND" inspect "$ref" | sed -n 's/^ *bounds: \[\(.*\)\] \.\. \[\(.*\)\]$/\1,\2/p' | tr -d ' ')"
    for time in $times; do
      frond_args=(render "$ref" --time "$time" --size "$size" --azimuth "$FROND_GODOT_AZIMUTH" \
        --elevation "$FROND_GODOT_ELEVATION" -o "$out/$stem.t$time.frond.png")
      [ -z "$clip" ] || frond_args+=(--clip "$clip")
      "$FROND" "${frond_args[@]}" > /dev/null
    done
  fi
  printf '%s\t%s\n' "$src" "$res" >> "$proj/frond_import.txt"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$src" "$res" "$out/$stem" "$times" "$clip" "$bounds" "$vat" >> "$proj/frond_inspect.txt"
done

# 1. Import with the editor (the plugin imports the files one by one, then kills the editor:
#    exit status 137 is the expected end; the result file says whether all were imported).
export FROND_GODOT_LOG="$out/godot_import.log"
set +e
timeout 900 xvfb-run -a -s "-screen 0 1024x768x24" \
  "$godot" --audio-driver Dummy --editor --path "$proj" > "$out/godot_import.stdout" 2> "$FROND_GODOT_LOG"
status=$?
set -e
if ! grep -q '"done":true' "$proj/frond_import_result.txt" 2>/dev/null; then
  echo "run.sh: the Godot editor import did not finish (exit status $status); see $FROND_GODOT_LOG" >&2
  tail -n 20 "$FROND_GODOT_LOG" >&2
  exit 1
fi

# 2. Load, describe and render each model as a game.
export FROND_GODOT_LOG="$out/godot_inspect.log"
set +e
timeout 600 xvfb-run -a -s "-screen 0 1024x768x24" \
  "$godot" --audio-driver Dummy --path "$proj" --resolution "$size" -s res://inspect.gd \
  > "$out/godot_inspect.stdout" 2> "$FROND_GODOT_LOG"
status=$?
set -e
grep '^{"' "$out/godot_inspect.stdout" > "$out/results.jsonl" || true
cat "$out/results.jsonl"
lines=$(wc -l < "$out/results.jsonl")
if [ "$status" -ne 0 ] || [ "$lines" -ne $# ]; then
  echo "run.sh: Godot printed $lines of $# JSON lines (exit status $status); see $FROND_GODOT_LOG" >&2
  tail -n 20 "$FROND_GODOT_LOG" >&2
  exit 1
fi
