#!/bin/sh
# Cross-compiles the core (src/core), the telemetry (src/telemetry) and the firmware application (firmware/src/app, all
# of the firmware that needs no ESP8266 Arduino core) with Debian's xtensa-lx106 GCC, as
# for the NodeMCU, and reports flash (text: code, literals, read-only data) and static
# RAM (data + bss) with xtensa-lx106-elf-size. Fails when the core is over its budget:
# 32.5 KiB text, 2 KiB static RAM. Also prints sizeof of the big objects on the target.
#
#   sh scripts/cross-compile.sh [--header battsim_config.h] [-o DIR]
#
# Needs the Debian packages gcc-xtensa-lx106 (compiler, no C++ library headers) and
# picolibc-xtensa-lx106-elf (the C headers: math.h, stdio.h, string.h). The code uses C
# headers only, so no libstdc++ is needed. --header also compiles the exported config
# (battsim export-config --firmware) for the target and checks it is a constant expression.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
cxx=${XTENSA_CXX:-xtensa-lx106-elf-g++}
size_tool=${XTENSA_SIZE:-xtensa-lx106-elf-size}
nm_tool=${XTENSA_NM:-xtensa-lx106-elf-nm}
ar_tool=${XTENSA_AR:-xtensa-lx106-elf-ar}
# 32 KiB until the forty-eighth session; raised by 512 B for three corrections a user sees
# (docs/firmware.md, "Size on the ESP8266"), with 137 B of it found again first.
text_budget=${CORE_TEXT_BUDGET:-33280}
ram_budget=${CORE_RAM_BUDGET:-2048}
header=""
out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --header) header=$2; shift 2 ;;
    -o) out=$2; shift 2 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "cross-compile: unknown argument $1" >&2; exit 2 ;;
  esac
done

for tool in "$cxx" "$size_tool" "$nm_tool" "$ar_tool"; do
  command -v "$tool" >/dev/null 2>&1 || {
    echo "cross-compile: $tool not found; apt-get install gcc-xtensa-lx106 picolibc-xtensa-lx106-elf" >&2
    exit 2
  }
done
if ! echo '#include <math.h>' | "$cxx" -x c++ -fsyntax-only - 2>/dev/null; then
  echo "cross-compile: the xtensa compiler has no math.h; apt-get install picolibc-xtensa-lx106-elf" >&2
  exit 2
fi

if [ -z "$out" ]; then
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT INT TERM
fi
mkdir -p "$out/core" "$out/app" "$out/telemetry"

# As the ESP8266 Arduino core builds: long calls, literals beside the code, sections per
# function; plus the core's own rules (no exceptions, no RTTI, no double promotion).
flags="-std=c++17 -Os -mlongcalls -mtext-section-literals -ffunction-sections -fdata-sections
  -fno-exceptions -fno-rtti -fno-threadsafe-statics -Wall -Wextra -Werror=double-promotion
  -I$root/src -I$root/firmware/src"

compile_dir() {  # compile_dir SRC_DIR OUT_DIR: every .cpp below SRC_DIR
  find "$1" -name '*.cpp' | sort | while read -r src; do
    obj="$2/$(echo "${src#"$root"/}" | tr '/' '_' | sed 's/\.cpp$/.o/')"
    # shellcheck disable=SC2086
    "$cxx" $flags -c "$src" -o "$obj" || { echo "cross-compile: FAILED $src" >&2; exit 1; }
  done
}
compile_dir "$root/src/core" "$out/core"
compile_dir "$root/src/telemetry" "$out/telemetry"
compile_dir "$root/firmware/src/app" "$out/app"
"$ar_tool" rcs "$out/libbattsim_core.a" "$out"/core/*.o
"$ar_tool" rcs "$out/libbattsim_telemetry.a" "$out"/telemetry/*.o
"$ar_tool" rcs "$out/libbattsim_fw_app.a" "$out"/app/*.o

# Sizes of the objects the firmware keeps in RAM, read from symbol sizes on the target.
cat > "$out/sizes.cpp" <<'EOF'
#include "app/logger_app.h"
#include "app/monitor_app.h"
#include "core/monitor.h"
char size_of_core_Monitor[sizeof(battsim::core::Monitor)];
char size_of_core_MonitorStatus[sizeof(battsim::core::MonitorStatus)];
char size_of_core_MonitorConfig[sizeof(battsim::core::MonitorConfig)];
char size_of_fw_MonitorApp[sizeof(battsim::fw::MonitorApp)];
char size_of_fw_LoggerApp[sizeof(battsim::fw::LoggerApp)];
EOF
# shellcheck disable=SC2086
"$cxx" $flags -c "$out/sizes.cpp" -o "$out/sizes.o"

if [ -n "$header" ]; then
  cat > "$out/config_check.cpp" <<EOF
#include "$(cd "$(dirname "$header")" && pwd)/$(basename "$header")"
constexpr battsim::core::MonitorConfig kConfig = battsim_generated::monitor_config();
static_assert(kConfig.cells_in_series > 0, "the exported config is a constant expression on the target");
const battsim::core::MonitorConfig* exported_config() { return &kConfig; }
EOF
  # shellcheck disable=SC2086
  "$cxx" $flags -c "$out/config_check.cpp" -o "$out/config_check.o"
  echo "exported config $header: compiles for xtensa as a constant expression"
  # The Arduino layer, compiled (not linked) against our declarations of the library APIs
  # it calls (firmware/host/arduino-api/README.md), with this config header.
  # The layer includes the header as battsim_config.h, whatever this one is called.
  mkdir -p "$out/arduino"
  cp "$header" "$out/arduino/battsim_config.h"
  for src in "$root"/firmware/src/arduino/*.cpp; do
    # shellcheck disable=SC2086
    "$cxx" $flags -Werror -I"$root/firmware/host/arduino-api" -I"$out/arduino" \
      -c "$src" -o "$out/arduino/$(basename "$src" .cpp).o" || { echo "cross-compile: FAILED $src" >&2; exit 1; }
  done
  echo "firmware Arduino layer (src/arduino, against firmware/host/arduino-api): compiles for xtensa," \
    "text $("$size_tool" -t "$out"/arduino/*.o | tail -n 1 | awk '{print $1}') B before the libraries"
fi

totals() {  # totals ARCHIVE -> "text data bss"
  "$size_tool" -t "$1" | tail -n 1 | awk '{print $1, $2, $3}'
}
set -- $(totals "$out/libbattsim_core.a")
core_text=$1 core_data=$2 core_bss=$3
set -- $(totals "$out/libbattsim_telemetry.a")
tel_text=$1 tel_data=$2 tel_bss=$3
set -- $(totals "$out/libbattsim_fw_app.a")
app_text=$1 app_data=$2 app_bss=$3
core_ram=$((core_data + core_bss))
rodata() {  # rodata OBJ_DIR: bytes of .rodata* (inside "text" above)
  "$size_tool" -A "$1"/*.o | awk '$1 ~ /^\.rodata/ {s += $2} END {print s + 0}'
}
core_rodata=$(rodata "$out/core")
app_rodata=$(rodata "$out/app")
tel_rodata=$(rodata "$out/telemetry")

echo "xtensa-lx106 ($("$cxx" -dumpversion)), -Os, per object (text = flash incl. literals and read-only data):"
"$size_tool" -t "$out/libbattsim_core.a" | sed 's/^/  /'
"$size_tool" -t "$out/libbattsim_telemetry.a" | sed 's/^/  /'
"$size_tool" -t "$out/libbattsim_fw_app.a" | sed 's/^/  /'
echo "library functions the core needs from the C library (not counted above):"
"$nm_tool" -u "$out/libbattsim_core.a" | awk 'NF && $NF !~ /:$/ {print $NF}' | sort -u > "$out/undef.txt"
"$nm_tool" --defined-only "$out/libbattsim_core.a" | awk 'NF==3 {print $3}' | sort -u > "$out/def.txt"
echo "  $(comm -23 "$out/undef.txt" "$out/def.txt" | tr '\n' ' ')"
echo "sizeof on the target:"
"$nm_tool" -S -t d "$out/sizes.o" | awk '/size_of_/ {sub("size_of_", "", $4); printf "  %-22s %6d bytes\n", $4, $2 + 0}'
echo "core:     text $core_text B (budget $text_budget), static RAM $core_ram B = data $core_data + bss $core_bss (budget $ram_budget)"
echo "telemetry (src/telemetry): text $tel_text B, static RAM $((tel_data + tel_bss)) B"
echo "firmware app: text $app_text B, static RAM $((app_data + app_bss)) B = data $app_data + bss $app_bss"
# The ESP8266 Arduino core's linker script keeps .rodata in RAM (hence PROGMEM), so these
# bytes cost RAM there too, on top of data + bss.
echo "read-only data within text (in RAM on the ESP8266 unless PROGMEM): core $core_rodata B, telemetry $tel_rodata B, firmware app $app_rodata B"

status=0
if [ "$core_text" -gt "$text_budget" ]; then
  echo "cross-compile: FAIL: core text $core_text B is over the $text_budget B budget" >&2
  status=1
fi
if [ "$core_ram" -gt "$ram_budget" ]; then
  echo "cross-compile: FAIL: core static RAM $core_ram B is over the $ram_budget B budget" >&2
  status=1
fi
[ "$status" -eq 0 ] && echo "cross-compile: core within budget"
exit "$status"
