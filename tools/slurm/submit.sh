#!/usr/bin/env bash
# Submits a tiled surfcap run to Slurm: one job array per stage of
# WORK/plan.json, each stage depending (afterok) on every array of the previous one, then the
# merge depending on the last. Prints the job ids, one line per submitted job.
#
#   tools/slurm/submit.sh WORK [sbatch options for every job, e.g. --partition=cpu --account=x]
#
# Environment: SURFCAP   the surfcap binary (default: `surfcap` on PATH), same path on all nodes;
#              MAX_ARRAY largest array to submit (default 1000: Slurm's default MaxArraySize is
#                        1001); a larger stage goes in several arrays, each told its OFFSET;
#              STAGES    the stages in order (default: those of `surfcap tiles plan`).
# Logs: WORK/slurm-logs/<job name>-<array job>_<task>.out. A failed task cancels the jobs
# that depend on it (--kill-on-invalid-dep=yes); jobs are idempotent, so running submit.sh
# again runs only the missing ones (done jobs exit at once).
set -euo pipefail
die() { echo "submit.sh: $*" >&2; exit 1; }
[ $# -ge 1 ] || die "usage: tools/slurm/submit.sh WORK [sbatch options...]"
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
[ -d "$1" ] || die "$1: no such work folder (make it with \`surfcap tiles plan SUBJECT -o $1\`)"
WORK=$(cd "$1" && pwd)
shift
[ -f "$WORK/plan.json" ] || die "$WORK/plan.json is missing: make the work folder with \`surfcap tiles plan SUBJECT -o $WORK\`"
SURFCAP=${SURFCAP:-surfcap}
if [[ "$SURFCAP" == */* ]]; then
  [ -x "$SURFCAP" ] || die "SURFCAP=$SURFCAP: no such executable"
  SURFCAP=$(cd "$(dirname "$SURFCAP")" && pwd)/$(basename "$SURFCAP")
else
  SURFCAP=$(command -v "$SURFCAP") || die "SURFCAP=${SURFCAP}: not on PATH (set SURFCAP to the binary's path)"
fi
MAX_ARRAY=${MAX_ARRAY:-1000}
[[ "$MAX_ARRAY" =~ ^[1-9][0-9]*$ ]] || die "MAX_ARRAY=$MAX_ARRAY: expected a count >= 1"
STAGES=${STAGES:-distances table scale candidates paths}
command -v sbatch >/dev/null || die "sbatch is not on PATH (run this on a Slurm login node)"
logs="$WORK/slurm-logs"
mkdir -p "$logs"

submit() { # sbatch --parsable prints "id" or "id;cluster"
  local out
  out=$(sbatch --parsable "$@") || die "sbatch $* failed"
  out=${out%%;*}
  [[ "$out" =~ ^[0-9]+$ ]] || die "sbatch printed \"$out\", expected a job id"
  echo "$out"
}

after=() # the arrays of the previous stage
for stage in $STAGES; do
  jobs=$("$SURFCAP" tiles count "$WORK" --stage "$stage") || die "\`$SURFCAP tiles count $WORK --stage $stage\` failed"
  [[ "$jobs" =~ ^[0-9]+$ ]] || die "\`surfcap tiles count\` printed \"$jobs\" for stage $stage, expected a count"
  [ "$jobs" -gt 0 ] || continue
  dep=()
  [ ${#after[@]} -eq 0 ] || dep=("--dependency=afterok:$(IFS=:; echo "${after[*]}")" --kill-on-invalid-dep=yes)
  ids=()
  for ((offset = 0; offset < jobs; offset += MAX_ARRAY)); do
    n=$((jobs - offset < MAX_ARRAY ? jobs - offset : MAX_ARRAY))
    id=$(submit --array="0-$((n - 1))" --job-name="surfcap-$stage" --output="$logs/%x-%A_%a.out" \
      --export="ALL,OFFSET=$offset" "${dep[@]}" "$@" \
      "$here/surfcap-tiles.sbatch" "$WORK" "$stage" "$SURFCAP")
    echo "$stage jobs $offset-$((offset + n - 1)): array $id"
    ids+=("$id")
  done
  after=("${ids[@]}")
done
[ ${#after[@]} -gt 0 ] || die "$WORK: no stage has jobs"
id=$(submit --job-name=surfcap-merge --output="$logs/%x-%j.out" \
  "--dependency=afterok:$(IFS=:; echo "${after[*]}")" --kill-on-invalid-dep=yes "$@" \
  "$here/surfcap-merge.sbatch" "$WORK" "$SURFCAP")
echo "merge: job $id"
