#!/usr/bin/env bash
# Installs the build into a scratch prefix, then builds and runs a consumer project against it
# the way an ECU project would, and runs the installed valve-decode on the sample trace.
# Usage: install_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build_dir=$1
source_dir=$2
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

cmake --install "$build_dir" --prefix "$scratch/prefix" >/dev/null

for f in bin/valve-decode bin/valve-sim bin/teejet-gateway bin/valvectl bin/teejet-record bin/teejet-replay \
  bin/teejet-web share/teejet-web/www/index.html share/teejet-web/www/dashboard.js \
  share/teejet-web/www/plot.js share/teejet-web/www/setup.js share/teejet-web/www/dashboard.css \
  share/teejet/idl/valve.idl include/teejet/valve.h \
  include/teejet/valvePubSubTypes.h include/teejet/valveTypeObject.h \
  include/teejet/codec/codec.hpp include/teejet/dds/participant.hpp \
  include/teejet/client/valve_view.hpp lib/cmake/TeejetDds/TeejetDdsConfig.cmake \
  share/teejet/profiles/fastdds-loopback.xml share/teejet/profiles/fastdds-lan-discovery-client.xml \
  share/teejet/gateway.example.yaml share/teejet/teejet-gateway.service \
  share/teejet/security/governance.xml bin/teejet-pki; do
  [ -e "$scratch/prefix/$f" ] || { echo "FAIL: not installed: $f"; exit 1; }
done

cmake -S "$source_dir/tests/install/consumer" -B "$scratch/consumer" \
  -DCMAKE_PREFIX_PATH="$scratch/prefix" >/dev/null
cmake --build "$scratch/consumer" >/dev/null
output=$("$scratch/consumer/consumer")
[ "$output" = "TJV123456 123.4" ] || { echo "FAIL: consumer printed '$output'"; exit 1; }

decoded=$(echo '(1700000000.000123) can0 18EFD5D8#020384' | "$scratch/prefix/bin/valve-decode")
expected='{"t":1700000000.000123,"iface":"can0","dir":"from_valve","addr":216,"msg":"position","fields":{"degrees":90.0}}'
[ "$decoded" = "$expected" ] || { echo "FAIL: installed valve-decode printed '$decoded'"; exit 1; }
# The installed teejet-pki finds its templates in the prefix: a site with a gateway's profile.
"$scratch/prefix/bin/teejet-pki" init "$scratch/site" --site install-test >/dev/null
"$scratch/prefix/bin/teejet-pki" issue "$scratch/site" gateway gw >/dev/null
"$scratch/prefix/bin/teejet-pki" profile "$scratch/site" gw \
  --base "$scratch/prefix/share/teejet/profiles/fastdds-loopback.xml" >/dev/null
grep -q 'dds.sec.auth.plugin' "$scratch/site/gw.xml" ||
  { echo "FAIL: the installed teejet-pki made no secure profile"; exit 1; }

echo "installed package: consumer built and ran, valve-decode decoded, teejet-pki made a site"
