#!/bin/bash
# Interrupts a run of inhand_scenario with a signal once its temporary output files
# exist, and checks that the program dies of that signal and leaves nothing behind
# (no temporary file, and not the output directory it created).
#   signal_check.sh <inhand_scenario> <scenario.json> <out dir> <INT|TERM|HUP>
set -u
exe=$1 scenario=$2 out=$3 sig=$4
rm -rf "$out"
set -m  # job control: the background run does not ignore SIGINT
"$exe" "$scenario" --out "$out" --quiet &
pid=$!
for _ in $(seq 1 400); do  # up to 20 s for the temporary trace file to appear
  compgen -G "$out/.trace.csv.*" >/dev/null && break
  sleep 0.05
done
sleep 0.2  # well into the simulation
echo "before the signal: $(ls -A "$out" 2>&1 | tr '\n' ' ')"
if ! kill -s "$sig" "$pid"; then
  echo "FAIL: the run ended before it could be sent SIG$sig"
  exit 1
fi
wait "$pid"
rc=$?
expected=$((128 + $(kill -l "$sig")))
if [ "$rc" -ne "$expected" ]; then
  echo "FAIL: exit status $rc, expected $expected (killed by SIG$sig)"
  exit 1
fi
if [ -e "$out" ]; then
  echo "FAIL: the interrupted run left $out behind: $(ls -A "$out" | tr '\n' ' ')"
  exit 1
fi
echo "killed by SIG$sig, nothing left behind"
