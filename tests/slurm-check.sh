#!/bin/bash
# Campaigns on Slurm, end to end on this machine: starts a private single-node Slurm (munged,
# slurmctld, slurmd; every file in a temporary directory, free ports, no accounting, no
# cgroups), submits a campaign of 40 move-bottle runs with seed 7 as a 4-task job array with
# tools/slurm/submit, waits for its merge job, runs the same campaign locally
# (tools/cram-plans-run --batch 40 --seed 7 --jobs 2) and checks that the merged results and
# the summaries equal the local ones. Stops everything it started, and checks that nothing is
# left running. Prints ok/FAIL lines and "slurm-check: N passed, M failed"; exits 1 on a failure.
# Installs nothing: without slurm-wlm and munge it only says so (make check-slurm installs them).
# Needs root (the daemons run as root) and a built checkout (make build).
# SLURM_CHECK_KEEP=1 keeps the temporary directory (logs, results) even on success.
set -u
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
root=$(cd "$(dirname "$0")/.." && pwd)
py=/usr/bin/python3
runs=40 seed=7 tasks=4 wait_limit=360

for d in slurmctld slurmd munged; do
  if ! command -v "$d" >/dev/null 2>&1; then
    echo "slurm-check: skipped: slurm-wlm not installed; run make check-slurm"
    exit 0
  fi
done

passed=0 failed=0
ok()  { passed=$((passed + 1)); echo "ok   $1"; }
bad() { failed=$((failed + 1)); echo "FAIL $1"; }
show() { # the last lines of a log file, indented
  [ -s "$1" ] && { echo "  --- ${1#$tmp/} (last ${2:-15} lines)"; tail -n "${2:-15}" "$1" | sed 's/^/  | /'; }
  return 0
}

started=$(date +%s)
tmp=$(mktemp -d /tmp/slurm-check.XXXXXX)
chmod 755 "$tmp"          # munged wants every directory above its socket searchable by all
conf=$tmp/slurm.conf
munge_pid= ctld_pid= slurmd_pid= finished=

alive() { [ -n "$1" ] && kill -0 "$1" 2>/dev/null; }
# processes started by this check: the daemons and everything they or the jobs started carry
# SLURM_CONF=$conf in their environment (this shell's own environment does not)
ours() {
  local p pid
  for p in /proc/[0-9]*; do
    pid=${p#/proc/}
    [ "$pid" = $$ ] && continue
    grep -qzxF "SLURM_CONF=$conf" "$p/environ" 2>/dev/null && echo "$pid"
  done
}
stop() { # stop PID (TERM, then KILL after 10 s)
  local pid=$1 i
  alive "$pid" || return 0
  kill "$pid" 2>/dev/null
  for ((i = 0; i < 50; i++)); do alive "$pid" || return 0; sleep 0.2; done
  kill -KILL "$pid" 2>/dev/null
  sleep 0.2
}

finish() {
  local rc=$? left p
  [ -n "$finished" ] && return
  finished=1
  trap - INT TERM
  # cancel what is still queued or running, let slurmd clean up, then stop the daemons
  if alive "$ctld_pid"; then
    ids=$(squeue -h -o %A 2>/dev/null)
    if [ -n "$ids" ]; then
      scancel $ids 2>/dev/null
      for ((i = 0; i < 50; i++)); do [ -z "$(squeue -h -o %A 2>/dev/null)" ] && break; sleep 0.3; done
    fi
  fi
  stop "$slurmd_pid"
  stop "$ctld_pid"
  unset SLURM_CONF
  for p in $(ours); do stop "$p"; done        # slurmstepd or job processes left behind
  [ -s "$tmp/munge/munged.pid" ] && munge_pid=$(cat "$tmp/munge/munged.pid")
  stop "$munge_pid"
  left=
  for p in $munge_pid $ctld_pid $slurmd_pid $(ours); do alive "$p" && left="$left $p"; done
  if [ -z "$left" ]; then
    ok "stopped munged, slurmctld and slurmd; nothing of this check left running"
  else
    bad "left running:$(for p in $left; do printf ' %s(%s)' "$p" "$(tr '\0' ' ' </proc/$p/cmdline 2>/dev/null | cut -c1-40)"; done)"
  fi
  [ "$rc" -ne 0 ] && [ "$failed" -eq 0 ] && bad "slurm-check ended early (status $rc)"
  if [ "$failed" -gt 0 ] || [ -n "${SLURM_CHECK_KEEP:-}" ]; then
    echo "slurm-check: logs and results kept in $tmp"
  else
    rm -rf "$tmp"
  fi
  echo "slurm-check: wall time $(($(date +%s) - started)) s"
  echo "slurm-check: $passed passed, $failed failed"
  [ "$failed" -eq 0 ] && exit 0 || exit 1
}
trap finish EXIT
trap 'exit 130' INT TERM

# ---- munge: a private key and socket ----------------------------------------------------------
mkdir -m 755 "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$tmp/munge/munge.key"
sock=$tmp/munge/munge.sock
munged --force --socket="$sock" --key-file="$tmp/munge/munge.key" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/munge/munged.log" \
  --seed-file="$tmp/munge/munged.seed" >"$tmp/munge/munged.out" 2>&1
for ((i = 0; i < 25; i++)); do [ -s "$tmp/munge/munged.pid" ] && break; sleep 0.2; done
munge_pid=$(cat "$tmp/munge/munged.pid" 2>/dev/null)
if alive "$munge_pid" && munge --socket="$sock" -n 2>/dev/null | unmunge --socket="$sock" >/dev/null 2>&1; then
  ok "munged (pid $munge_pid) on a private socket encodes and decodes a credential"
else
  bad "munged did not start on $sock"
  show "$tmp/munge/munged.out"; show "$tmp/munge/munged.log"
  exit 1
fi

# ---- a single-node Slurm ----------------------------------------------------------------------
read -r ctld_port slurmd_port < <("$py" -c '
import socket
ss = [socket.socket() for _ in range(2)]
for s in ss: s.bind(("127.0.0.1", 0))
print(*[s.getsockname()[1] for s in ss])')
# this machine's CPUs, sockets, cores and memory, as slurmd sees them
node=$(slurmd -C 2>/dev/null | grep -m1 '^NodeName=' | sed 's/^NodeName=[^ ]* *//; s/ *$//')
[ -n "$node" ] || node="CPUs=$(nproc)"
mkdir -p "$tmp/state" "$tmp/spool"
cat >"$conf" <<EOF
# a private single-node cluster of tests/slurm-check.sh
ClusterName=cramcheck
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$sock
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
MailProg=/bin/true
# no cgroups in a container
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
MinJobAge=600
NodeName=localhost NodeAddr=127.0.0.1 $node State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$conf
slurmctld -D >"$tmp/slurmctld.out" 2>&1 &
ctld_pid=$!
slurmd -D -N localhost >"$tmp/slurmd.out" 2>&1 &
slurmd_pid=$!
state=
for ((i = 0; i < 60; i++)); do
  state=$(sinfo -h -n localhost -o %T 2>/dev/null)
  [ "$state" = idle ] && break
  alive "$ctld_pid" && alive "$slurmd_pid" || break
  sleep 0.5
done
if [ "$state" = idle ]; then
  ok "slurmctld (port $ctld_port) and slurmd (port $slurmd_port) up; sinfo: node localhost idle ($node)"
else
  bad "single-node Slurm did not come up (node state '${state}')"
  show "$tmp/slurmctld.log"; show "$tmp/slurmd.log"; show "$tmp/slurmctld.out" 5; show "$tmp/slurmd.out" 5
  exit 1
fi

# ---- the campaign on Slurm --------------------------------------------------------------------
if "$root/tools/slurm/submit" --batch "$runs" --seed "$seed" --tasks 0 --out "$tmp/bad" >/dev/null 2>&1; then
  bad "tools/slurm/submit rejects --tasks 0"
else
  ok "tools/slurm/submit rejects --tasks 0"
fi

out=$tmp/campaign
t0=$(date +%s)
if ids=$("$root/tools/slurm/submit" --batch "$runs" --seed "$seed" --tasks "$tasks" --out "$out" \
           --partition debug --parsable 2>"$tmp/submit.err") \
   && read -r array merge <<<"$ids" && [[ $array =~ ^[0-9]+$ && $merge =~ ^[0-9]+$ ]]; then
  ok "submitted $runs runs (seed $seed) as array job $array (--array=1-$tasks) and merge job $merge"
else
  bad "tools/slurm/submit failed: $ids"; show "$tmp/submit.err"
  exit 1
fi

job_state() { scontrol show job -o "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p'; }
mstate=
for ((i = 0; i < wait_limit; i += 2)); do
  mstate=$(job_state "$merge")
  case $mstate in PENDING|CONFIGURING|RUNNING|COMPLETING|"") sleep 2 ;; *) break ;; esac
done
slurm_seconds=$(($(date +%s) - t0))
tstates=$(scontrol show job -o "$array" 2>/dev/null | sed -n 's/.*ArrayTaskId=\([0-9]*\).*JobState=\([A-Z_]*\).*/\1:\2/p' | sort -n | paste -sd ' ')
if [ "$(grep -o ':COMPLETED' <<<"$tstates" | wc -l)" -eq "$tasks" ]; then
  ok "all $tasks array tasks completed ($tstates)"
else
  bad "array tasks: ${tstates:-no state} (expected $tasks COMPLETED)"
  for f in "$out"/slurm-*.out; do [ -e "$f" ] && show "$f" 8; done
fi
if [ "$mstate" = COMPLETED ]; then
  ok "merge job $merge completed; the campaign took $slurm_seconds s on Slurm"
else
  bad "merge job $merge: ${mstate:-no state} after $slurm_seconds s (limit $wait_limit s)"
  for f in "$out"/merge-*.out; do [ -e "$f" ] && show "$f" 8; done
  show "$tmp/slurmctld.log" 8
fi
missing=
for ((i = 1; i <= tasks; i++)); do [ -s "$out/shard-$i.jsonl" ] || missing="$missing shard-$i.jsonl"; done
for f in results.jsonl summary.txt; do [ -s "$out/$f" ] || missing="$missing $f"; done
if [ -z "$missing" ]; then
  ok "wrote shard-1..$tasks.jsonl ($(cat "$out"/shard-*.jsonl | wc -l) lines), results.jsonl ($(wc -l <"$out/results.jsonl") lines), summary.txt"
else
  bad "missing or empty in $out:$missing"
fi

# ---- the same campaign locally, and the comparisons ------------------------------------------
t0=$(date +%s)
if (cd "$tmp" && "$root/tools/cram-plans-run" --batch "$runs" --seed "$seed" --jobs 2 \
      --results "$tmp/local.jsonl" >"$tmp/local.out" 2>&1) \
   && "$root/tools/cram-plans-run" --summary "$tmp/local.jsonl" >"$tmp/local-summary.txt" 2>"$tmp/local-summary.err"; then
  ok "local campaign (--jobs 2) ran in $(($(date +%s) - t0)) s: $(head -1 "$tmp/local-summary.txt")"
else
  bad "local campaign failed"; show "$tmp/local.out"; show "$tmp/local-summary.err"
fi

if [ -s "$out/results.jsonl" ] && [ -s "$tmp/local.jsonl" ]; then
  # run index order, and every deterministic field equal ("seconds" is wall time)
  if msg=$("$py" - "$out/results.jsonl" "$tmp/local.jsonl" "$runs" <<'EOF' 2>&1
import json, re, sys
merged_path, local_path, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
def load(path):
    return [json.loads(l) for l in open(path) if l.strip()]
merged, local = load(merged_path), load(local_path)
problems = []
order = [r.get("index") for r in merged]
if order != list(range(n)):
    problems.append("results.jsonl is not runs 0..%d in index order: %s" % (n - 1, order[:12]))
# wall times and where a run ran differ between machines and runs; every other field must not
# and "sweeps": motions a plan runs in parallel (PAR) are sweep-checked against each other's
# state at that moment, so how many paths touch something depends on the threads' timing
varies = lambda k: bool(re.search(r"seconds|time|wall|host|pid|worker|rss|heap|sweeps|_m?s$", k))
strip = lambda r: {k: v for k, v in r.items() if not varies(k)}
a = {r["index"]: strip(r) for r in merged}
b = {r["index"]: strip(r) for r in local}
if sorted(a) != sorted(b):
    problems.append("indices differ: Slurm %d runs, local %d runs" % (len(a), len(b)))
differ = [i for i in sorted(set(a) & set(b)) if a[i] != b[i]]
if differ:
    i = differ[0]
    keys = sorted(k for k in set(a[i]) | set(b[i]) if a[i].get(k) != b[i].get(k))
    problems.append("%d runs differ, first run %d in %s: Slurm %s, local %s"
                    % (len(differ), i, keys, [a[i].get(k) for k in keys], [b[i].get(k) for k in keys]))
if problems:
    print("; ".join(problems)); sys.exit(1)
ok = sum(1 for r in merged if r.get("success") is True)
ignored = sorted({k for r in merged + local for k in r if varies(k)})
print("%d runs, %d succeeded, %d fields each; not compared: %s"
      % (len(merged), ok, len(strip(merged[0])) if merged else 0, ", ".join(ignored) or "none"))
EOF
  ); then
    ok "merged results equal the local ones, run by run in index order ($msg)"
  else
    bad "merged results differ from the local ones: $msg"
  fi
else
  bad "no results to compare"
fi

if [ -s "$out/summary.txt" ] && [ -s "$tmp/local-summary.txt" ]; then
  # the same summary but for its timing and sweep lines (see above) and the order in which
  # failures are listed
  norm() { grep -Eiv 'time|wall|elapsed|sweeps' "$1" | sort; }
  if diff <(norm "$out/summary.txt") <(norm "$tmp/local-summary.txt") >"$tmp/summary.diff"; then
    ok "summaries agree: $(head -1 "$out/summary.txt")"
  else
    bad "summaries differ (Slurm <, local >)"; show "$tmp/summary.diff" 20
  fi
else
  bad "no summaries to compare"
fi
exit 0
