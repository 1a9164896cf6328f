#!/usr/bin/env bash
# `unav datagen --backend slurm` against a real single-node Slurm cluster that this test starts
# (munged + slurmctld + slurmd from Debian, private config, key, sockets and ports; as root, as
# the README's test command runs): a sweep of 3 samples as a job array of 2 tasks, waited for;
# every sample finished with its manifest, identical to the same samples rendered locally.
source "$(dirname "$0")/common.sh"
fail() { echo "FAIL: $*"; for f in "$d"/*.log "$d"/out/slurm/*.log; do [ -f "$f" ] && { echo "--- $f"; tail -15 "$f"; }; done; exit 1; }
[ "$(id -u)" -eq 0 ] || { echo "FAIL: the Slurm round trip starts slurmd, which needs root (run the test command as root)"; exit 1; }
for b in munged slurmctld slurmd sbatch; do
  command -v "$b" >/dev/null || [ -x "/usr/sbin/$b" ] || { echo "FAIL: $b missing (scripts/install_deps.sh installs it)"; exit 1; }
done
d=$(mktemp -d)
cleanup() {
  # The daemons are found by their private config/socket path (pid files may lag behind).
  scontrol shutdown >/dev/null 2>&1 || true
  for _ in $(seq 1 20); do pgrep -f "$d/slurm.conf" >/dev/null || break; sleep 0.25; done
  pkill -9 -f "$d/slurm.conf" 2>/dev/null || true
  pkill -f "$d/munge.sock" 2>/dev/null || true
  sleep 0.3
  rm -rf "$d"
}
trap cleanup EXIT
host=$(hostname -s)
port=$((20000 + $$ % 20000))
dd if=/dev/urandom of="$d/munge.key" bs=1024 count=1 2>/dev/null
chmod 400 "$d/munge.key"
mkdir -p "$d/state" "$d/spool"
/usr/sbin/munged --force --key-file="$d/munge.key" --socket="$d/munge.sock" --pid-file="$d/munged.pid" \
  --log-file="$d/munged.log" --seed-file="$d/munge.seed"
cat >"$d/slurm.conf" <<CONF
ClusterName=unavtest$$
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$d/munge.sock
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$d/state
SlurmdSpoolDir=$d/spool
SlurmctldPidFile=$d/slurmctld.pid
SlurmdPidFile=$d/slurmd.pid
SlurmctldLogFile=$d/slurmctld.log
SlurmdLogFile=$d/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
PlugStackConfig=/dev/null
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=4000 State=UNKNOWN
PartitionName=unavtest Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$d/slurm.conf"
/usr/sbin/slurmctld -i -f "$d/slurm.conf"
/usr/sbin/slurmd -f "$d/slurm.conf"
for _ in $(seq 1 60); do sinfo -h -o %t 2>/dev/null | grep -q idle && break; sleep 0.5; done
sinfo -h -o %t | grep -q idle || fail "the single-node cluster did not come up: $(sinfo 2>&1)"

spec="$d/spec.yaml"
shipped_spec "$spec" "s|  frames: .*|  frames: 5|" "s|  width: .*|  width: 160|" "s|  height: .*|  height: 120|" \
  "s|  cpus_per_task: .*|  cpus_per_task: 1|" "s|  mem: .*|  mem: 1G|"
printf '  array_size: 2\n' >>"$spec"
timeout 300 unav datagen "$spec" -n 3 --out "$d/out" --backend slurm --wait >"$d/submit.log" 2>&1 \
  || { cat "$d/submit.log"; fail "slurm sweep failed"; }
grep -q "submitted job [0-9]* and waited for it" "$d/submit.log" || { cat "$d/submit.log"; fail "no job id"; }
grep -q "3/3 samples finished" "$d/submit.log" || { cat "$d/submit.log"; fail "not every sample finished"; }
grep -q "^#SBATCH --array=0-1$" "$d/out/slurm/unav_datagen.sbatch" || fail "job array size"
grep -q "^#SBATCH --mem=1G$" "$d/out/slurm/unav_datagen.sbatch" || fail "resource request from the spec"
logs=$(ls "$d"/out/slurm/task_*_*.log | wc -l)
[ "$logs" -eq 2 ] || fail "$logs task logs, expected 2"
# The same samples rendered locally are byte-identical to the cluster's.
unav datagen "$spec" -n 3 --out "$d/local" >/dev/null 2>&1 || fail "local sweep failed"
for i in 0 1 2; do
  cmp -s "$d/out/sample_00000$i/manifest.json" "$d/local/sample_00000$i/manifest.json" || fail "sample $i differs"
done
echo "1 passed, 0 failed"
