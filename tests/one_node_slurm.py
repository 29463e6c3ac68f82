"""A one-node Slurm cluster on this machine for the tests: Debian 12's slurmctld + slurmd (22.05)
and munge, started as root in a temporary folder with their own key and config (no systemd, no
cgroups: proctrack/linuxproc, task/none), stopped and removed on exit. The machine's cores and
memory are the node's. Clients find it through SLURM_CONF in `env`."""
import ctypes
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from pathlib import Path

DAEMONS = ("slurmctld", "slurmd", "munged", "mungekey", "sbatch", "squeue", "scontrol")


def missing_programs():
    return [p for p in DAEMONS if shutil.which(p) is None]


def _node_line():
    # slurmd -C prints this machine as a NodeName line; Slurm 22.05's parser wants Sockets=.
    out = subprocess.run(["slurmd", "-C"], capture_output=True, text=True, check=True).stdout
    line = out.splitlines()[0]
    words = [w for w in line.split() if not w.startswith("Boards=")]
    return " ".join(w.replace("SocketsPerBoard=", "Sockets=") for w in words)


CONFIG = """ClusterName=sirltest
SlurmctldHost={host}
SlurmUser=root
SlurmdUser=root
SlurmctldPort={ctld_port}
SlurmdPort={d_port}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={dir}/msock/munge.socket,cred_expire=10
StateSaveLocation={dir}/state
SlurmdSpoolDir={dir}/spool
SlurmctldPidFile={dir}/slurmctld.pid
SlurmdPidFile={dir}/slurmd.pid
SlurmctldLogFile={dir}/log/slurmctld.log
SlurmdLogFile={dir}/log/slurmd.log
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
ReturnToService=2
KillWait=20
MinJobAge=600
SchedulerParameters=bf_interval=1,sched_interval=2
{node} State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
"""


def _dies_with_parent():
    """In the child, before exec: SIGTERM when the process that started it dies, so a test killed
    mid-way (SIGKILL, a ctest timeout) leaves no daemon running on the machine."""
    PR_SET_PDEATHSIG = 1
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


class OneNodeSlurm:
    """with OneNodeSlurm() as s: subprocess.run([...], env=s.env)"""

    def __enter__(self):
        self.dir = Path(tempfile.mkdtemp(prefix="sirl-slurm-"))
        self.procs = []
        d = self.dir
        os.chmod(d, 0o755)  # munged: every folder above its socket must be searchable
        for sub in ("state", "spool", "log", "msock", "munge"):
            (d / sub).mkdir()
        os.chmod(d / "munge", 0o700)  # the key's folder stays private
        try:
            self._start(d)
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def _start(self, d):
        subprocess.run(["mungekey", "--create", f"--keyfile={d}/munge/munge.key"], check=True)
        # In the foreground (no fork), so that it dies with this process; ready once its socket is.
        # (Each daemon writes its log through its own copy of the file; ours is closed at once.)
        with open(d / "log" / "munged.stderr", "w") as log:
            self.munged = subprocess.Popen(
                ["munged", "--foreground", f"--socket={d}/msock/munge.socket",
                 f"--key-file={d}/munge/munge.key", f"--pid-file={d}/munge/munged.pid",
                 f"--log-file={d}/log/munged.log", f"--seed-file={d}/munge/munged.seed"],
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=log,
                preexec_fn=_dies_with_parent)
        deadline = time.time() + 30
        while not (d / "msock" / "munge.socket").exists():
            if self.munged.poll() is not None or time.time() > deadline:
                raise RuntimeError("munged did not start:\n" + self.logs())
            time.sleep(0.05)
        # Ports of our own, so a stale daemon elsewhere on the machine is never talked to.
        ports = []
        for _ in range(2):
            with socket.socket() as s:
                s.bind(("127.0.0.1", 0))
                ports.append(s.getsockname()[1])
        host = socket.gethostname().split(".")[0]
        (d / "slurm.conf").write_text(CONFIG.format(host=host, dir=d, node=_node_line(),
                                                    ctld_port=ports[0], d_port=ports[1]))
        self.env = dict(os.environ, SLURM_CONF=str(d / "slurm.conf"))
        for daemon in ("slurmctld", "slurmd"):
            with open(d / "log" / f"{daemon}.stdout", "w") as log:
                self.procs.append(subprocess.Popen([daemon, "-D", "-f", str(d / "slurm.conf")],
                                                   stdout=log, stderr=subprocess.STDOUT,
                                                   env=self.env, preexec_fn=_dies_with_parent))
        deadline = time.time() + 60
        while time.time() < deadline:
            p = subprocess.run(["sinfo", "-h", "-o", "%T"], capture_output=True, text=True,
                               env=self.env)
            if p.returncode == 0 and p.stdout.split() == ["idle"]:
                return
            time.sleep(0.5)
        raise RuntimeError("the one-node Slurm did not become idle:\n" + self.logs())

    def logs(self):
        out = []
        for f in sorted((self.dir / "log").glob("*")):
            out.append(f"--- {f.name}\n" + "\n".join(f.read_text(errors="replace").splitlines()[-30:]))
        return "\n".join(out)

    def run(self, *cmd, check=True, timeout=120):
        p = subprocess.run(list(cmd), capture_output=True, text=True, env=self.env,
                           stdin=subprocess.DEVNULL, timeout=timeout)
        if check and p.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
        return p

    def queue(self):
        """{job id: state} of every job Slurm still knows (array tasks as ID_i)."""
        p = self.run("squeue", "-h", "-r", "-t", "all", "-o", "%i %T")
        return dict(line.split() for line in p.stdout.splitlines() if line.strip())

    def wait_idle(self, timeout=600):
        """Waits until no job is pending, running or completing."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            p = self.run("squeue", "-h", "-o", "%i %T")
            if not p.stdout.strip():
                return
            time.sleep(1)
        raise RuntimeError("jobs still queued after %d s:\n%s" % (timeout, p.stdout))

    def __exit__(self, *exc):
        env = getattr(self, "env", None)
        if env and self.procs:
            # Drain the queue first: slurmd waits for a job still completing before it stops.
            subprocess.run(["scancel", "--user=root"], env=env, capture_output=True)
            for _ in range(60):
                p = subprocess.run(["squeue", "-h"], env=env, capture_output=True, text=True)
                if p.returncode != 0 or not p.stdout.strip():
                    break
                time.sleep(0.5)
            subprocess.run(["scontrol", "shutdown"], env=env, capture_output=True)
        for proc in self.procs:
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        munged = getattr(self, "munged", None)
        if munged is not None:
            munged.terminate()
            try:
                munged.wait(timeout=15)
            except subprocess.TimeoutExpired:
                munged.kill()
                munged.wait()
        shutil.rmtree(self.dir, ignore_errors=True)
