"""A real single-node SLURM cluster for tests: Debian's munge + slurmctld + slurmd, no systemd.

Everything lives in one temporary folder (config, key, sockets, state, logs); the daemons listen
on free ports so that several clusters (other test sessions) can coexist on one machine. They are
started here and stopped by the PIDs they wrote — never by name. `sacct` does not work without
slurmdbd, so a small stand-in answering from `squeue --states=all` is put first on PATH (with
MinJobAge=3600 finished jobs stay visible to squeue); submitit asks sacct for job states.

    with SlurmCluster(tmp_path) as cluster:
        env = cluster.env()            # SLURM_CONF + PATH for subprocesses
        ...

The binaries are REQUIRED: a missing one raises (make test installs them with apt-get).
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import stat
import subprocess
import time
from pathlib import Path

BINARIES = ("munged", "mungekey", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "scancel")

#: `sacct -o JobID,State,NodeList --parsable2 -j ID[,ID...]` (what submitit calls) from squeue.
SACCT_STANDIN = r"""#!/usr/bin/env python3
# sacct stand-in for a cluster without slurmdbd: answers submitit's query from `squeue --states=all`.
import subprocess, sys
args = sys.argv[1:]
ids = []
for i, a in enumerate(args):
    if a == "-j" and i + 1 < len(args):
        ids = args[i + 1].split(",")
    elif a.startswith("--jobs="):
        ids = a.split("=", 1)[1].split(",")
out = subprocess.run(["squeue", "--states=all", "--noheader", "--array", "--format=%i|%T|%N"],
                     capture_output=True, text=True).stdout
wanted = {i.split("_")[0] for i in ids}
print("JobID|State|NodeList")
for line in out.splitlines():
    jid, state, nodes = (line.split("|") + ["", "", ""])[:3]
    if not ids or jid.split("_")[0] in wanted:
        print(f"{jid}|{state}|{nodes or 'None assigned'}")
"""


#: [s] the credential lifetime, and so the hold of a requeued job (AuthInfo cred_expire)
CRED_EXPIRE = 10


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def missing_binaries() -> list[str]:
    return [b for b in BINARIES if shutil.which(b) is None]


class SlurmCluster:
    """munged + slurmctld + slurmd on localhost, configured and run inside `root`."""

    def __init__(self, root: Path, cpus: int = 2, memory_mb: int = 2000, partition: str = "debug"):
        missing = missing_binaries()
        if missing:
            raise RuntimeError(f"SLURM test cluster needs {', '.join(missing)}: run `make test` (installs "
                               "munge slurmctld slurmd slurm-client with apt-get)")
        self.root = Path(root)
        self.cpus, self.memory_mb, self.partition = cpus, memory_mb, partition
        self.conf = self.root / "slurm.conf"
        self.bin = self.root / "bin"
        self.pidfiles = {n: self.root / f"{n}.pid" for n in ("munged", "slurmctld", "slurmd")}

    # ---- setup ---------------------------------------------------------------------------
    def _write_config(self) -> None:
        r = self.root
        for d in ("state", "spool", "munge", "log"):
            (r / d).mkdir(parents=True, exist_ok=True)
        # munged insists on a 0755 socket folder and a private key
        os.chmod(r, 0o755)
        os.chmod(r / "munge", 0o755)
        self.key = r / "munge" / "munge.key"
        subprocess.run(["mungekey", "-c", "-f", "-k", str(self.key)], check=True, capture_output=True)
        os.chmod(self.key, 0o600)
        self.socket = r / "munge" / "munge.sock"
        user = os.environ.get("USER") or __import__("pwd").getpwuid(os.getuid()).pw_name
        lines = {
            "ClusterName": "interphase-test",
            "SlurmctldHost": "localhost",
            "SlurmctldPort": _free_port(),
            "SlurmdPort": _free_port(),
            "SlurmUser": user,
            "SlurmdUser": user,
            "AuthType": "auth/munge",
            "CredType": "cred/munge",
            # cred_expire: how long a requeued job is held before it may start again (default 120 s,
            # SLURM 22.05); a job released sooner is refused by slurmd ("Job credential revoked")
            "AuthInfo": f"socket={self.socket},cred_expire={CRED_EXPIRE}",
            "StateSaveLocation": r / "state",
            "SlurmdSpoolDir": r / "spool",
            "SlurmctldPidFile": self.pidfiles["slurmctld"],
            "SlurmdPidFile": self.pidfiles["slurmd"],
            "SlurmctldLogFile": r / "log" / "slurmctld.log",
            "SlurmdLogFile": r / "log" / "slurmd.log",
            "ProctrackType": "proctrack/linuxproc",
            "TaskPlugin": "task/none",
            "SelectType": "select/cons_tres",
            "SelectTypeParameters": "CR_CPU",
            "AccountingStorageType": "accounting_storage/none",
            "JobAcctGatherType": "jobacct_gather/none",
            "JobCompType": "jobcomp/none",
            "MpiDefault": "none",
            "ReturnToService": 2,
            "MinJobAge": 3600,
            "KillWait": 5,
            "SchedulerType": "sched/builtin",
            # the main scheduling loop every 2 s (default 60 s): a requeued job starts soon after its hold
            "SchedulerParameters": "sched_interval=2",
        }
        text = "\n".join(f"{k}={v}" for k, v in lines.items())
        text += (f"\nNodeName=localhost NodeAddr=127.0.0.1 CPUs={self.cpus} RealMemory={self.memory_mb} State=UNKNOWN"
                 f"\nPartitionName={self.partition} Nodes=localhost Default=YES MaxTime=INFINITE State=UP\n")
        self.conf.write_text(text)
        self.bin.mkdir(exist_ok=True)
        sacct = self.bin / "sacct"
        sacct.write_text(SACCT_STANDIN)
        sacct.chmod(sacct.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)

    def env(self, base: dict | None = None) -> dict:
        """Environment for clients (sbatch, squeue, submitit): this cluster's config, the sacct stand-in."""
        env = dict(os.environ if base is None else base)
        env["SLURM_CONF"] = str(self.conf)
        env["PATH"] = f"{self.bin}{os.pathsep}{env.get('PATH', '')}"
        return env

    def _wait_pidfile(self, name: str, timeout: float = 15.0) -> int:
        deadline = time.monotonic() + timeout
        path = self.pidfiles[name]
        while time.monotonic() < deadline:
            try:
                pid = int(path.read_text().strip())
                os.kill(pid, 0)
                return pid
            except (OSError, ValueError):
                time.sleep(0.1)
        raise RuntimeError(f"{name} did not start; see {self.root / 'log'}")

    def start(self) -> "SlurmCluster":
        self._write_config()
        r = self.root
        subprocess.run(["munged", f"--socket={self.socket}", f"--key-file={self.key}",
                        f"--pid-file={self.pidfiles['munged']}", f"--log-file={r / 'log' / 'munged.log'}",
                        f"--seed-file={r / 'munge' / 'munge.seed'}", "--force"], check=True,
                       capture_output=True)
        self._wait_pidfile("munged")
        env = self.env()
        subprocess.run(["slurmctld", "-f", str(self.conf)], check=True, env=env, capture_output=True)
        self._wait_pidfile("slurmctld")
        subprocess.run(["slurmd", "-f", str(self.conf), "-N", "localhost"], check=True, env=env, capture_output=True)
        self._wait_pidfile("slurmd")
        self.wait_idle()
        return self

    def wait_idle(self, timeout: float = 30.0) -> None:
        deadline = time.monotonic() + timeout
        state = ""
        while time.monotonic() < deadline:
            out = subprocess.run(["sinfo", "-h", "-o", "%T"], capture_output=True, text=True, env=self.env())
            state = out.stdout.strip()
            if state.startswith("idle") or state.startswith("mixed"):
                return
            time.sleep(0.3)
        raise RuntimeError(f"SLURM node not idle after {timeout} s (state {state!r}); see {self.root / 'log'}")

    # ---- teardown ------------------------------------------------------------------------
    def stop(self) -> None:
        """Stop the daemons by their PID files, slurmd first; SIGKILL whatever ignores SIGTERM."""
        for name in ("slurmd", "slurmctld", "munged"):
            try:
                pid = int(self.pidfiles[name].read_text().strip())
            except (OSError, ValueError):
                continue
            try:
                os.kill(pid, signal.SIGTERM)
            except ProcessLookupError:
                continue
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline:
                try:
                    os.kill(pid, 0)
                except ProcessLookupError:
                    break
                time.sleep(0.1)
            else:
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass

    def __enter__(self) -> "SlurmCluster":
        try:
            return self.start()
        except BaseException:
            self.stop()
            raise

    def __exit__(self, *exc) -> None:
        self.stop()
