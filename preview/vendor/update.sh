#!/usr/bin/env bash
# Rebuilds the vendored three.js bundle from the pinned npm packages (needs Node and network;
# run by hand when the pin changes, never by the build or CI). The output is committed.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm init -y > /dev/null
npm install --no-audit --no-fund --silent three@0.187.0 esbuild@0.25.10
cp "$here/three-entry.js" entry.js
# One classic (IIFE) script, window.FROND_THREE: a classic script also runs from a file:// page,
# where browsers refuse ES modules. KTX2Loader's default transcoder URL (import.meta.url, which a
# classic script lacks) resolves against the page instead; the page sets the path anyway.
npx esbuild entry.js --bundle --minify --format=iife --global-name=FROND_THREE \
  --legal-comments=eof --define:import.meta.url=document.baseURI \
  --outfile="$here/frond-three.js"
cp node_modules/three/examples/jsm/libs/basis/basis_transcoder.js \
  node_modules/three/examples/jsm/libs/basis/basis_transcoder.wasm "$here/"
cp node_modules/three/LICENSE "$here/LICENSE-three"
