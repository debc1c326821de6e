#!/usr/bin/env bash
# The inn demo (`./run demo [--quality Q] [--window|--headless]` builds, then execs this):
# generates the inn with Draco-compressed meshes into demo-out/, cooks it with build/bin/lightpatch,
# and plays it: in a window when a display is present (or with --window), otherwise the scripted
# scenario headless (EGL surfaceless), printing the folder with its screenshots and frames.csv.
#   --quality draft|preview|production   cook quality (default preview: the whole demo stays
#                                        within about ten minutes on a 2-core machine;
#                                        production is the slow, beautiful option)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BIN=$ROOT/build/bin
OUT=$ROOT/demo-out
quality=preview
mode=auto
while (($#)); do
  case "$1" in
    --quality)
      [ $# -ge 2 ] || { echo "demo: --quality needs draft, preview or production" >&2; exit 2; }
      quality=$2; shift 2 ;;
    --quality=*) quality=${1#--quality=}; shift ;;
    --window) mode=window; shift ;;
    --headless) mode=headless; shift ;;
    -h|--help) sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "demo: unknown option '$1' (--quality Q, --window, --headless)" >&2; exit 2 ;;
  esac
done
case "$quality" in draft|preview|production) ;; *) echo "demo: --quality must be draft, preview or production, not '$quality'" >&2; exit 2 ;; esac
for b in lightpatch lightpatch-inn; do
  [ -x "$BIN/$b" ] || { echo "demo: $BIN/$b is missing; run ./run build (or ./run demo)" >&2; exit 1; }
done
if [ "$mode" = auto ]; then
  if [ -n "${DISPLAY:-}" ]; then mode=window; else mode=headless; fi
fi

mkdir -p "$OUT"
log() { printf '\033[1m== %s\033[0m\n' "$*" >&2; }
log "generate the inn (Draco) into $OUT/inn.glb"
"$BIN/lightpatch-inn" generate -o "$OUT/inn.glb" --draco
log "cook it ($quality quality)"
start=$(date +%s)
"$BIN/lightpatch" cook "$OUT/inn.glb" -o "$OUT/inn.lpk" --quality "$quality" --report "$OUT/cook-report.json" --quiet
echo "cooked in $(( $(date +%s) - start )) s; stage times in $OUT/cook-report.json"
"$BIN/lightpatch" info "$OUT/inn.lpk" | grep -E "light map|atlas bytes|^$OUT" || true

if [ "$mode" = window ]; then
  log "play (W A S D walk, mouse or arrow keys look, E uses, Esc quits)"
  exec "$BIN/lightpatch-inn" play --scene "$OUT/inn.glb" --pack "$OUT/inn.lpk"
fi
log "play the scripted scenario headless"
rm -rf "$OUT/run"
status=0
"$BIN/lightpatch-inn" play --headless --script default --scene "$OUT/inn.glb" --pack "$OUT/inn.lpk" --out "$OUT/run" || status=$?
echo "screenshots, frames.csv, steps.csv and summary.json are in $OUT/run"
exit $status
