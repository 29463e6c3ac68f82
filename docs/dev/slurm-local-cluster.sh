#!/bin/bash
# One-node Slurm (Debian 12 slurm-wlm 22.05) in a temp dir, as root, no systemd.
# usage: source slurm-local-cluster.sh; slurm_up; ...; slurm_down
# Needs: apt-get install -y --no-install-recommends slurmctld slurmd slurm-client munge
slurm_up() {
  set -e
  SLURM_DIR=${SLURM_DIR:-$(mktemp -d /tmp/slurm-ci.XXXXXX)}
  chmod 755 "$SLURM_DIR"                     # munged: socket dir must be world-x
  mkdir -p "$SLURM_DIR"/{state,spool,log,msock,munge}
  chmod 700 "$SLURM_DIR/munge"; chmod 755 "$SLURM_DIR/msock"
  mungekey --create --keyfile="$SLURM_DIR/munge/munge.key"
  munged --socket="$SLURM_DIR/msock/munge.socket" --key-file="$SLURM_DIR/munge/munge.key" \
         --pid-file="$SLURM_DIR/munge/munged.pid" --log-file="$SLURM_DIR/log/munged.log" \
         --seed-file="$SLURM_DIR/munge/munged.seed"           # forks; returns when socket is ready
  local H NODE
  H=$(hostname -s)
  NODE=$(slurmd -C | head -1 | sed 's/ Boards=[0-9]*//; s/SocketsPerBoard=/Sockets=/')
  cat > "$SLURM_DIR/slurm.conf" <<CONF
ClusterName=ci
SlurmctldHost=$H
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$SLURM_DIR/msock/munge.socket,cred_expire=10
StateSaveLocation=$SLURM_DIR/state
SlurmdSpoolDir=$SLURM_DIR/spool
SlurmctldPidFile=$SLURM_DIR/slurmctld.pid
SlurmdPidFile=$SLURM_DIR/slurmd.pid
SlurmctldLogFile=$SLURM_DIR/log/slurmctld.log
SlurmdLogFile=$SLURM_DIR/log/slurmd.log
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=100
JobRequeue=1
RequeueExit=85
ReturnToService=2
KillWait=5
SchedulerParameters=bf_interval=1,sched_interval=2
PreemptType=preempt/partition_prio
PreemptMode=REQUEUE
SlurmctldParameters=preempt_send_user_signal
$NODE State=UNKNOWN
PartitionName=low  Nodes=ALL Default=YES MaxTime=INFINITE State=UP PriorityTier=1  PreemptMode=REQUEUE GraceTime=15
PartitionName=high Nodes=ALL Default=NO  MaxTime=INFINITE State=UP PriorityTier=10 PreemptMode=OFF
CONF
  export SLURM_CONF="$SLURM_DIR/slurm.conf" SLURM_DIR
  slurmctld -D -f "$SLURM_CONF" >"$SLURM_DIR/log/slurmctld.stdout" 2>&1 &
  echo $! > "$SLURM_DIR/slurmctld.bgpid"
  slurmd -D -f "$SLURM_CONF" >"$SLURM_DIR/log/slurmd.stdout" 2>&1 &
  echo $! > "$SLURM_DIR/slurmd.bgpid"
  set +e
  local i s
  for i in $(seq 1 120); do
    s=$(sinfo -h -o %T 2>/dev/null | sort -u)
    [ "$s" = idle ] && return 0
    sleep 0.5
  done
  echo "slurm did not become idle (state='$s')" >&2; tail -20 "$SLURM_DIR"/log/*.log >&2; return 1
}
slurm_down() {
  [ -n "$SLURM_DIR" ] || return 0
  scancel --user=root 2>/dev/null
  local i
  for i in $(seq 1 60); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.5; done
  scontrol shutdown 2>/dev/null          # stops slurmctld and (when idle) slurmd
  for p in slurmd slurmctld; do
    local pid; pid=$(cat "$SLURM_DIR/$p.bgpid" 2>/dev/null) || continue
    for i in $(seq 1 40); do kill -0 "$pid" 2>/dev/null || break; sleep 0.25; done
    kill -0 "$pid" 2>/dev/null && { kill -TERM "$pid"; sleep 2; kill -KILL "$pid" 2>/dev/null; }
    wait "$pid" 2>/dev/null
  done
  munged --socket="$SLURM_DIR/msock/munge.socket" --stop
  rm -rf "$SLURM_DIR"; unset SLURM_DIR SLURM_CONF
}
