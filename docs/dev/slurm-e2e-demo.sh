#!/bin/bash
# End-to-end check used for the research notes. Prints "N passed, N failed".
. "$(dirname "$0")/slurm-local-cluster.sh"
pass=0; fail=0
ok()  { echo "PASS: $*"; pass=$((pass+1)); }
bad() { echo "FAIL: $*"; fail=$((fail+1)); }
state() { scontrol show job "$1" | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p'; }
restarts() { scontrol show job "$1" | sed -n 's/.*Restarts=\([0-9]*\).*/\1/p'; }
waitgone() { local i; for i in $(seq 1 ${2:-240}); do [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0; sleep 0.5; done; return 1; }
t0=$(date +%s)
slurm_up || exit 1
echo "cluster idle after $(( $(date +%s)-t0 ))s, dir=$SLURM_DIR"; O=$SLURM_DIR/out; mkdir -p $O
trap slurm_down EXIT

# 1. plain job + array, sbatch --wait
sbatch --wait -o $O/h-%j.out --wrap hostname >/dev/null && grep -qx "$(hostname)" $O/h-*.out && ok hostname || bad hostname
sbatch --wait --array=0-2 -c 1 --mem=50M -o $O/a-%A_%a.out --wrap 'echo task=$SLURM_ARRAY_TASK_ID' >/dev/null \
  && [ "$(cat $O/a-*.out | sort | tr '\n' ' ')" = "task=0 task=1 task=2 " ] && ok array || bad array

# 2. self-requeue on --signal=B:USR1 before time limit
cat > $SLURM_DIR/ckpt.sh <<'S'
#!/bin/bash
echo "start restart=${SLURM_RESTART_COUNT:-0}"
[ -n "$SLURM_RESTART_COUNT" ] && { echo resumed; exit 0; }
trap 'echo got USR1; scontrol requeue $SLURM_JOB_ID; exit 0' USR1
for i in $(seq 1 300); do sleep 1 & wait $!; done
S
J=$(sbatch --parsable --requeue --open-mode=append --time=1 --signal=B:USR1@30 -o $O/ck-%j.out $SLURM_DIR/ckpt.sh)
ts=$(date +%s); waitgone $J 300
echo "self-requeue job took $(( $(date +%s)-ts ))s"; cat $O/ck-$J.out
[ "$(state $J)" = COMPLETED ] && [ "$(restarts $J)" = 1 ] && grep -q 'start restart=1' $O/ck-$J.out && ok signal-requeue || bad signal-requeue

# 3. RequeueExit=85 on one array task
J=$(sbatch --parsable --array=0-1 --open-mode=append -o $O/re-%A_%a.out --wrap '[ "$SLURM_ARRAY_TASK_ID" = 1 ] && [ -z "$SLURM_RESTART_COUNT" ] && exit 85; echo ok restart=${SLURM_RESTART_COUNT:-0}')
ts=$(date +%s); waitgone $J 300; echo "requeue-exit array took $(( $(date +%s)-ts ))s"
[ "$(restarts ${J}_1)" = 1 ] && [ "$(state ${J}_1)" = COMPLETED ] && [ "$(restarts ${J}_0)" = 0 ] && ok requeue-exit || bad requeue-exit

# 4. preemption: low job (whole node) preempted by high job, gets USR1, is requeued, reruns
cat > $SLURM_DIR/pre.sh <<'S'
#!/bin/bash
echo "start restart=${SLURM_RESTART_COUNT:-0}"
[ -n "$SLURM_RESTART_COUNT" ] && exit 0
trap 'echo got USR1; scontrol requeue $SLURM_JOB_ID; exit 0' USR1
for i in $(seq 1 300); do sleep 1 & wait $!; done
S
L=$(sbatch --parsable -p low -c $(nproc) --mem=100M --time=10 --requeue --signal=B:USR1@60 --open-mode=append -o $O/low-%j.out $SLURM_DIR/pre.sh)
for i in $(seq 1 40); do [ "$(state $L)" = RUNNING ] && break; sleep 0.5; done; sleep 1
ts=$(date +%s)
H=$(sbatch --parsable -p high -c $(nproc) --mem=100M -o $O/high-%j.out --wrap 'echo high')
waitgone $H 120; waitgone $L 300; echo "preemption scenario took $(( $(date +%s)-ts ))s"; cat $O/low-$L.out
[ "$(state $H)" = COMPLETED ] && [ "$(state $L)" = COMPLETED ] && [ "$(restarts $L)" = 1 ] && grep -q 'got USR1' $O/low-$L.out && ok preempt-requeue || bad preempt-requeue

echo "total $(( $(date +%s)-t0 ))s"
echo "$pass passed, $fail failed"
[ $fail = 0 ]
