#!/usr/bin/env bash
# Runs every libFuzzer target (or the ones named) one after the other, starting from the
# committed seeds (fuzz/corpus/<name>) plus what earlier runs found (build/fuzz/corpus/<name>,
# not committed). Each target runs for FUZZ_SECONDS of wall time (default 60) or, when
# FUZZ_CPU_SECONDS is set, in 60 s chunks until it has used that much CPU time (user + sys: on
# a shared machine wall time says little). Crashes, leaks, timeouts and out-of-memory inputs land
# in build/fuzz/findings/<name>/. Prints one line per target: wall and CPU seconds, executions,
# corpus size, findings. Exit status 1 when any target produced a finding.
#   fuzz/run.sh [NAME...]
set -uo pipefail
cd "$(dirname "$0")/.."
bin=build/fuzz/fuzz
names=("$@")
[ ${#names[@]} -eq 0 ] && names=(nrrd metaimage nifti vtk vti slc mrc dicom ply obj off stl amh)
status=0
for n in "${names[@]}"; do
  work=build/fuzz/corpus/$n findings=build/fuzz/findings/$n
  mkdir -p "$work" "$findings"
  log=build/fuzz/$n.log
  : >"$log"
  wall=0 cpu=0 execs=0 rc=0
  while :; do
    chunk=${FUZZ_SECONDS:-60}
    # With a CPU budget: 60 s chunks, the last one only as long as what is left (at least 10 s).
    if [ -n "${FUZZ_CPU_SECONDS:-}" ]; then
      chunk=$((FUZZ_CPU_SECONDS - cpu))
      [ "$chunk" -gt 60 ] && chunk=60
      [ "$chunk" -lt 10 ] && chunk=10
    fi
    # -malloc_limit_mb: any single allocation above 2 GiB is a finding (the readers check sizes
    # against the file before allocating); -timeout: an input taking 10 s is a hang.
    TIMEFORMAT='%U %S'
    t=$( { time LSAN_OPTIONS=suppressions=fuzz/lsan.supp "$bin/fuzz_$n" "$work" "fuzz/corpus/$n" -max_total_time="$chunk" -timeout=10 \
      -malloc_limit_mb=2048 -rss_limit_mb=3072 -print_final_stats=1 \
      -artifact_prefix="$findings/" >>"$log" 2>&1; echo "rc=$?" >>"$log"; } 2>&1 )
    rc=$(grep -o '^rc=[0-9]*' "$log" | tail -1 | cut -d= -f2)
    cpu=$(echo "$t $cpu" | awk '{printf "%.0f", $1 + $2 + $3}')
    wall=$((wall + chunk))
    e=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
    execs=$((execs + ${e:-0}))
    # Ledger of every chunk ever run here (date, target, wall s, CPU s, executions): the totals
    # in docs/FUZZING.md are sums over it.
    printf '%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$n" "$chunk" \
      "$(echo "$t" | awk '{printf "%.1f", $1 + $2}')" "${e:-0}" >>build/fuzz/ledger.tsv
    [ "$rc" -ne 0 ] && break
    [ -z "${FUZZ_CPU_SECONDS:-}" ] && break
    [ "$cpu" -ge "$FUZZ_CPU_SECONDS" ] && break
  done
  found=$(find "$findings" -type f | wc -l)
  # fuzz_dicom only: inputs that crashed GDCM inside the reader's child process (third-party,
  # handled as errors by adamesh; fuzz_reader.cpp triage_child_crash).
  third=$(find "build/fuzz/third-party/$n" -type f ! -name '*.log' 2>/dev/null | wc -l)
  printf '%-10s %6ss wall %6ss CPU  %10s execs  corpus %5s  findings %s  GDCM crashes %s  (exit %s, log %s)\n' \
    "$n" "$wall" "$cpu" "$execs" "$(ls "$work" | wc -l)" "$found" "$third" "$rc" "$log"
  if [ "$rc" -ne 0 ] || [ "$found" -ne 0 ]; then status=1; fi
done
exit $status
