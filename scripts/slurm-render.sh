#!/usr/bin/env bash
# Renders one image on a Slurm cluster: a job array of N `illum render --part K/N` tasks, one per
# array index, and a merge job that runs once every task succeeded (docs/farm.md).
#
#   scripts/slurm-render.sh SCENE -n N -o OUT.exr [options] [illum render options] [-- sbatch options]
#   scripts/slurm-render.sh --resubmit PARTS_DIR K[,K...] [--wait]
#
# Options:
#   -n N                 number of parts (array tasks 0..N-1)
#   -o OUT.exr           the merged image (also OUT.png if it ends in .png)
#   --split samples|tiles  how the parts cut the image (default samples; see docs/farm.md)
#   --parts DIR          where the parts, logs and generated batch scripts go
#                        (default: OUT without its extension, plus .parts; it must be on storage
#                        that every node sees)
#   --illum PATH         the illum binary every node runs (default: $ILLUM, else illum on PATH,
#                        else this checkout's target/release/illum)
#   --cpus-per-task C    CPUs per task (sbatch); lavapipe then uses C threads (LP_NUM_THREADS)
#   --gpus-per-task G    GPUs per render task (sbatch --gpus-per-task; the merge asks for none)
#   --wait               wait for the merge job and fail unless it completed
#   anything else before `--` is passed to `illum render` (e.g. --spp 1024 --seed 3
#   --width 1920); options after `--` go to both sbatch calls (e.g. --partition=render
#   --time=1:00:00 --account=lighting).
#
# Prints the job ids on stdout (ARRAY_JOB=… and MERGE_JOB=…), what it did on stderr. A failed
# or cancelled task cancels the merge job (--kill-on-invalid-dep); resubmit just that task with
# --resubmit, which also submits a new merge job. A task writes its part to a temporary file and
# renames it, so a killed task leaves no part behind, and the merge names any missing or broken
# part.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
me="$here/$(basename "$0")"

die() {
  echo "slurm-render: error: $*" >&2
  exit 2
}

# The ids sbatch --parsable prints: "id" or "id;cluster".
submit() {
  local out
  out=$(sbatch --parsable "$@") || die "sbatch $* failed"
  echo "${out%%;*}"
}

# Blocks until job $1 has left the queue; returns 0 if it completed.
wait_job() {
  local id=$1 state
  while :; do
    state=$(scontrol show job -o "$id" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
    case "$state" in
      PENDING | RUNNING | CONFIGURING | COMPLETING | SUSPENDED | REQUEUED | RESIZING) sleep 1 ;;
      COMPLETED) return 0 ;;
      "") echo "slurm-render: job $id is no longer known to scontrol" >&2; return 1 ;;
      *) echo "slurm-render: job $id ended $state" >&2; return 1 ;;
    esac
  done
}

# Submits the tasks in $1 (an --array spec) and a merge job after them; records both.
submit_tasks() {
  local spec=$1 array merge dep
  # shellcheck source=/dev/null
  source "$dir/job.sh"
  array=$(submit --array="$spec" --job-name="$name" --output="$dir/logs/part-%a.log" \
    "${task_opts[@]}" "${sbatch_opts[@]}" "$dir/task.sh")
  # Afterok on the new tasks; afterany on older arrays of this render still queued, so a merge
  # submitted by --resubmit does not start before them.
  dep="afterok:$array"
  if [ -f "$dir/arrays" ]; then
    while read -r old; do
      if [ -n "$(squeue -h -j "$old" -o %i 2>/dev/null)" ]; then dep="$dep,afterany:$old"; fi
    done <"$dir/arrays"
  fi
  merge=$(submit --dependency="$dep" --kill-on-invalid-dep=yes --job-name="$name-merge" \
    --output="$dir/logs/merge-%j.log" "${sbatch_opts[@]}" "$dir/merge.sh")
  echo "$array" >>"$dir/arrays"
  echo "$merge" >"$dir/merge.jobid"
  echo "slurm-render: array job $array (parts $spec of $n), merge job $merge into $out" >&2
  echo "slurm-render: parts and logs in $dir/" >&2
  echo "ARRAY_JOB=$array"
  echo "MERGE_JOB=$merge"
  if [ "$wait" = 1 ]; then wait_job "$merge"; fi
}

wait=0
if [ "${1:-}" = "--resubmit" ]; then
  [ $# -ge 3 ] || die "usage: $0 --resubmit PARTS_DIR K[,K...] [--wait]"
  dir=$(cd "$2" 2>/dev/null && pwd) || die "--resubmit $2: no such folder"
  [ -f "$dir/job.sh" ] || die "--resubmit $2: not a parts folder of slurm-render.sh (no job.sh)"
  spec=$3
  [ "${4:-}" = "--wait" ] && wait=1
  # shellcheck source=/dev/null
  source "$dir/job.sh"
  IFS=, read -ra ks <<<"$spec"
  for k in "${ks[@]}"; do
    [[ "$k" =~ ^[0-9]+$ ]] && [ "$k" -lt "$n" ] ||
      die "--resubmit $2 $spec: part \"$k\" is not a number from 0 to $((n - 1))"
  done
  # The merge job of the earlier submission: cancelled already if a task failed, else cancel it.
  if [ -f "$dir/merge.jobid" ]; then scancel "$(cat "$dir/merge.jobid")" 2>/dev/null || true; fi
  submit_tasks "$spec"
  exit 0
fi

[ $# -ge 1 ] || die "usage: $0 SCENE -n N -o OUT.exr [options] [illum render options] [-- sbatch options]"
scene=$1
shift
n="" out="" split=samples dir="" illum="${ILLUM:-}"
task_opts=() sbatch_opts=() illum_opts=()
while [ $# -gt 0 ]; do
  case "$1" in
    -n) n=${2:?-n needs a number}; shift 2 ;;
    -o | --output) out=${2:?-o needs a path}; shift 2 ;;
    --split) split=${2:?--split needs samples or tiles}; shift 2 ;;
    --parts) dir=${2:?--parts needs a folder}; shift 2 ;;
    --illum) illum=${2:?--illum needs a path}; shift 2 ;;
    --cpus-per-task) task_opts+=("--cpus-per-task=${2:?}"); shift 2 ;;
    --gpus-per-task) task_opts+=("--gpus-per-task=${2:?}"); shift 2 ;;
    --wait) wait=1; shift ;;
    --) shift; sbatch_opts=("$@"); break ;;
    --part | --part=* | --samples* | --crop* | --time | --time=* | --png | --reference* | --report*)
      die "$1: not for a farm render (slurm-render.sh sets the part; --time, --png, --reference and --report need the whole image)" ;;
    *) illum_opts+=("$1"); shift ;;
  esac
done
[ -f "$scene" ] || die "scene $scene: no such file"
[[ "$n" =~ ^[1-9][0-9]*$ ]] || die "-n \"$n\": the number of parts must be a whole number of at least 1"
[ -n "$out" ] || die "-o OUT.exr is required"
case "$out" in *.exr | *.png) ;; *) die "-o $out: the output must end in .exr or .png" ;; esac
case "$split" in samples | tiles) ;; *) die "--split $split: samples or tiles" ;; esac
if [ -z "$illum" ]; then
  illum=$(command -v illum || echo "$here/../target/release/illum")
fi
[ -x "$illum" ] || die "illum binary $illum: not found or not executable (build it, or give --illum PATH)"
command -v sbatch >/dev/null || die "sbatch not found: is Slurm installed here?"

abs() { echo "$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"; }
[ -d "$(dirname "$out")" ] || die "-o $out: folder $(dirname "$out") does not exist"
scene=$(abs "$scene")
out=$(abs "$out")
illum=$(abs "$illum")
[ -n "$dir" ] || dir="${out%.*}.parts"
mkdir -p "$dir/logs"
dir=$(cd "$dir" && pwd)
name="illum-$(basename "${out%.*}")"

# Shell-quoted words, for the generated scripts.
q() {
  local s=""
  if [ $# -gt 0 ]; then s=$(printf '%q ' "$@"); fi
  printf '%s' "${s% }"
}
cat >"$dir/task.sh" <<EOF
#!/usr/bin/env bash
# Part K of $n of $out: run by Slurm with \$SLURM_ARRAY_TASK_ID, or by hand as task.sh K.
set -euo pipefail
k=\${1:-\${SLURM_ARRAY_TASK_ID:?not a Slurm array task: give the part number}}
if [ -n "\${SLURM_CPUS_PER_TASK:-}" ] && [ -z "\${LP_NUM_THREADS:-}" ]; then
  export LP_NUM_THREADS=\$SLURM_CPUS_PER_TASK
fi
exec $(q "$illum" render "$scene") --part "\$k/$n" --split $split -o $(q "$dir")/part-"\$k".exr $(q "${illum_opts[@]}")
EOF
parts=""
for ((k = 0; k < n; k++)); do parts="$parts $(q "$dir/part-$k.exr")"; done
cat >"$dir/merge.sh" <<EOF
#!/usr/bin/env bash
# Merges the $n parts into $out (bit-identical to rendering it in one piece).
set -euo pipefail
missing=()
for ((k = 0; k < $n; k++)); do
  [ -f $(q "$dir")/part-"\$k".exr ] || missing+=("\$k")
done
if [ \${#missing[@]} -gt 0 ]; then
  list=\$(IFS=,; echo "\${missing[*]}")
  echo "illum merge: missing part(s) \$list of $n (no $(q "$dir")/part-K.exr): see $(q "$dir")/logs/part-K.log, then resubmit them: $(q "$me") --resubmit $(q "$dir") \$list" >&2
  exit 1
fi
exec $(q "$illum") merge $parts -o $(q "$out")
EOF
chmod +x "$dir/task.sh" "$dir/merge.sh"
{
  declare -p n out name task_opts sbatch_opts
} >"$dir/job.sh"
rm -f "$dir/arrays" "$dir/merge.jobid"
submit_tasks "0-$((n - 1))"
