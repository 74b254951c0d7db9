# shellcheck shell=bash
# shellcheck disable=SC2034  # KF_SLURM_WHY is read by the caller
# A throw-away single-node SLURM for the tests (sourced): munged, slurmctld and slurmd of the
# distribution's packages (Debian: munge slurmctld slurmd slurm-client, installed by
# scripts/lib.sh), started directly (no systemd) with everything under one directory:
#   kf_slurm_start DIR   writes DIR/slurm.conf, starts the daemons, exports SLURM_CONF;
#                        returns 1 with KF_SLURM_WHY set when they cannot start (the caller skips)
#   kf_slurm_stop        cancels the jobs left, stops the daemons it started (by their pid files)
# The node declares the CPUs the machine has (at least 2, with oversubscription of cores), the
# daemons run as root, and jobs are submitted by an ordinary user (kf_slurm_user).

KF_SLURM_DIR=""
KF_SLURM_WHY=""

kf_slurm_free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

kf_slurm_start() {
  local dir="$1" tool
  for tool in munged slurmctld slurmd sbatch scontrol; do
    if ! command -v "$tool" >/dev/null 2>&1; then
      KF_SLURM_WHY="'$tool' not installed (Debian: apt-get install munge slurmctld slurmd slurm-client)"
      return 1
    fi
  done
  if [ "$(id -u)" -ne 0 ]; then
    KF_SLURM_WHY="the SLURM daemons need root (slurmd starts jobs as their user); running as $(id -un)"
    return 1
  fi
  KF_SLURM_DIR="$dir"
  mkdir -p "$dir"/{munge,state,spool,log,run}
  chmod 755 "$dir" "$dir/run" "$dir/log"
  chmod 700 "$dir/munge"
  dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$dir/munge/munge.key"
  if ! munged --force --socket="$dir/run/munge.socket" --key-file="$dir/munge/munge.key" \
       --log-file="$dir/log/munged.log" --pid-file="$dir/run/munged.pid" \
       --seed-file="$dir/munge/munged.seed" 2>"$dir/log/munged.err"; then
    KF_SLURM_WHY="munged did not start: $(tail -n 3 "$dir/log/munged.err" "$dir/log/munged.log" 2>/dev/null | tr '\n' ' ')"
    return 1
  fi
  local host cpus ctl_port d_port
  host="$(hostname -s)"
  cpus="$(nproc)"
  [ "$cpus" -ge 2 ] || cpus=2
  ctl_port="$(kf_slurm_free_port)"
  d_port="$(kf_slurm_free_port)"
  # Job ids unique across runs: slurmstepd's PMIx directories (/tmp/spmix_appdir_<uid>_<job>.<step>)
  # of an earlier run with the same ids would make the step launch fail.
  first_id=$(( ($(date +%s) % 600000) * 100 + 1 ))
  cat >"$dir/slurm.conf" <<CONF
ClusterName=kftest
FirstJobId=$first_id
SlurmctldHost=$host
SlurmctldPort=$ctl_port
SlurmdPort=$d_port
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/run/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/log/jobcomp.txt
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
MinJobAge=3600
KillWait=5
OverTimeLimit=0
InactiveLimit=0
SchedulerParameters=sched_interval=2
NodeName=$host CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:4
CONF
  export SLURM_CONF="$dir/slurm.conf"
  slurmctld -f "$SLURM_CONF" 2>"$dir/log/slurmctld.err" \
    || { KF_SLURM_WHY="slurmctld did not start: $(tail -n 3 "$dir/log/slurmctld.log" "$dir/log/slurmctld.err" 2>/dev/null | tr '\n' ' ')"; return 1; }
  slurmd -f "$SLURM_CONF" 2>"$dir/log/slurmd.err" \
    || { KF_SLURM_WHY="slurmd did not start: $(tail -n 3 "$dir/log/slurmd.log" "$dir/log/slurmd.err" 2>/dev/null | tr '\n' ' ')"; return 1; }

  for _ in $(seq 1 30); do
    if sinfo -h -N -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
      return 0
    fi
    sleep 1
  done
  KF_SLURM_WHY="the node never became idle: $(sinfo -N 2>&1 | tr '\n' ' ') $(tail -n 3 "$dir/log/slurmd.log" | tr '\n' ' ')"
  return 1
}

kf_slurm_stop() {
  [ -n "$KF_SLURM_DIR" ] || return 0
  local f pid ids
  # Jobs still queued or running (a failed test) are cancelled first: a slurmstepd left behind by
  # a stopped slurmd would live on with its job.
  ids="$(squeue -h -o %i 2>/dev/null | tr '\n' ' ')"
  if [ -n "${ids// /}" ]; then
    # shellcheck disable=SC2086  # a list of job ids
    scancel $ids 2>/dev/null || true
    for _ in $(seq 1 30); do
      [ -z "$(squeue -h -o %i 2>/dev/null)" ] && ! pgrep -f "slurmstepd: \[" >/dev/null 2>&1 && break
      sleep 1
    done
  fi
  for f in slurmd slurmctld munged; do
    [ -r "$KF_SLURM_DIR/run/$f.pid" ] || continue
    pid="$(cat "$KF_SLURM_DIR/run/$f.pid")"
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 1 20); do kill -0 "$pid" 2>/dev/null || break; sleep 0.5; done
  done
  return 0
}
