# Shared by scripts/test (stage "fuzz") and scripts/fuzz (sourced, not run): builds the
# libFuzzer targets of fuzz/ with clang in a build directory and runs them for a
# bounded time. Expects $root to be the repository root.
#
#   fuzz_build DIR              configure + build the fuzzers in DIR (clang, Release)
#   fuzz_run DIR SECONDS T...   run targets T (default: all built) for SECONDS each, in
#                               parallel (one process per core), and print per target:
#                               "fuzz <target>: N executions in S s, ok" or "... FAILED"
#                               Returns non-zero if any target found a crash, a leak,
#                               a sanitizer report, a timeout or an out-of-memory.
# Corpora persist in DIR/corpus/<target> (the scenario fuzzer is seeded with
# scenarios/**/*.json, the URDF fuzzer with models/urdf/*.urdf); reproducers of findings go to DIR/artifacts/<target>/ and each
# run's log to DIR/logs/<target>.log.

INHAND_FUZZ_TARGETS=(fuzz_controller_update fuzz_scenario_json fuzz_urdf_reader)

# The clang C and C++ compilers (clang-14 names first, as Debian installs them).
fuzz_compilers() {
  local cxx cc
  for cxx in clang++-14 clang++; do command -v "$cxx" >/dev/null 2>&1 && break; done
  for cc in clang-14 clang; do command -v "$cc" >/dev/null 2>&1 && break; done
  if ! command -v "$cxx" >/dev/null 2>&1; then
    echo "fuzz: clang++ not found (install clang-14 and libclang-rt-14-dev)" >&2
    return 1
  fi
  echo "$cc $cxx"
}

fuzz_build() {
  local dir=$1 compilers cc cxx gen
  compilers=$(fuzz_compilers) || return 1
  read -r cc cxx <<<"$compilers"
  mapfile -t gen < <(inhand_generator_args "$dir")
  CC=$cc CXX=$cxx cmake "${gen[@]}" -S "$root" -B "$dir" \
    -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_COMPILE_WARNING_AS_ERROR=ON \
    -DINHAND_BUILD_FUZZERS=ON \
    -DINHAND_BUILD_TESTS=OFF -DINHAND_BUILD_EXAMPLES=OFF \
    -DINHAND_BUILD_BENCHMARKS=OFF -DINHAND_INSTALL=OFF || return 1
  cmake --build "$dir" -j"$(nproc)" || return 1
}

# Seeds a target's corpus directory (only files not already there).
fuzz_seed() {
  local target=$1 corpus=$2 f
  mkdir -p "$corpus"
  local seeds=()
  case $target in
    fuzz_scenario_json) seeds=("$root"/scenarios/*/*.json) ;;
    fuzz_urdf_reader) seeds=("$root"/models/urdf/*.urdf) ;;
  esac
  for f in "${seeds[@]}"; do
    if [[ -e $f && ! -e $corpus/seed_$(basename "$f") ]]; then cp "$f" "$corpus/seed_$(basename "$f")"; fi
  done
  return 0
}

fuzz_run() {
  local dir=$1 seconds=$2
  shift 2
  local targets=("$@") t exe pids=() names=() status=0 i rc runs
  if [[ ${#targets[@]} -eq 0 ]]; then
    for t in "${INHAND_FUZZ_TARGETS[@]}"; do
      [[ -x $dir/fuzz/$t ]] && targets+=("$t")
    done
  fi
  if [[ ${#targets[@]} -eq 0 ]]; then
    echo "fuzz: no fuzz target built in $dir/fuzz" >&2
    return 1
  fi
  mkdir -p "$dir/logs"
  for t in "${targets[@]}"; do
    exe=$dir/fuzz/$t
    if [[ ! -x $exe ]]; then
      echo "fuzz $t: not built" >&2
      status=1
      continue
    fi
    fuzz_seed "$t" "$dir/corpus/$t"
    mkdir -p "$dir/artifacts/$t"
    # -rss_limit_mb and -timeout turn memory blow-ups and hangs into findings; the leak
    # suppressions (scripts/lib/lsan.supp) name urdfdom's own leak, nothing of inhand's.
    LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/scripts/lib/lsan.supp} \
      "$exe" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$dir/artifacts/$t/" "$dir/corpus/$t" >"$dir/logs/$t.log" 2>&1 &
    pids+=($!)
    names+=("$t")
  done
  for i in "${!pids[@]}"; do
    rc=0
    wait "${pids[$i]}" || rc=$?
    t=${names[$i]}
    runs=$(grep -Eo '^stat::number_of_executed_units: *[0-9]+' "$dir/logs/$t.log" | grep -Eo '[0-9]+$' | tail -1 || true)
    if [[ $rc -eq 0 ]]; then
      echo "fuzz $t: ${runs:-?} executions in ${seconds} s, ok"
    else
      echo "fuzz $t: FAILED (exit $rc) after ${runs:-?} executions; log $dir/logs/$t.log, reproducer in $dir/artifacts/$t/"
      grep -E 'ERROR|SUMMARY|Test unit written|^ +#[0-9]+ .* in (inhand|LLVMFuzzer|\(anonymous)' "$dir/logs/$t.log" | head -20 || true
      status=1
    fi
  done
  return $status
}
