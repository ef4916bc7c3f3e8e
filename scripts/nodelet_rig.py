"""A private ROS graph around the acvo nodelet, for the measurement scripts (soak_nodelet,
bag_rate): a master on a free port, launch/acvo.launch (its own nodelet manager), the manager's
pid, its memory and CPU time from /proc, and the machine line printed with every figure.

Nothing here imports rospy at import time: the caller sets up the environment first
(ros_environment, apply_environment), then uses Listener or imports rospy itself.
"""
import datetime
import math
import os
import re
import signal
import socket
import subprocess
import threading
import time
import xmlrpc.client

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
WS = os.environ.get("ACVO_WS", os.path.join(ROOT, "build", "ws"))
MANAGER = "/acvo_manager"  # acvo.launch's manager for name:=acvo
ANSI = re.compile(r"\x1b\[[0-9;]*m")  # roscpp's colour codes in the launch log


class RigError(Exception):
    pass


def ros_environment(ws=WS):
    """os.environ as build/ws/devel/setup.bash leaves it (package path, message modules)."""
    setup = os.path.join(ws, "devel", "setup.bash")
    if not os.path.isfile(setup):
        raise RigError("%s is missing: build first (scripts/build)" % setup)
    out = subprocess.run(["bash", "-c", 'source "$0" && env -0', setup], capture_output=True,
                         check=True).stdout
    env = dict(item.split("=", 1) for item in out.decode().split("\0") if "=" in item)
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    return env


def apply_environment(env):
    """Makes this process see env (rospy reads ROS_MASTER_URI; acvo.msg needs PYTHONPATH)."""
    import sys
    os.environ.clear()
    os.environ.update(env)
    for path in reversed(env.get("PYTHONPATH", "").split(":")):
        if path and path not in sys.path:
            sys.path.insert(0, path)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# ------------------------------------------------------------------------------------------
# /proc
# ------------------------------------------------------------------------------------------
def proc_status(pid, key):
    """A KiB field of /proc/<pid>/status (VmRSS, VmHWM); None when the process is gone."""
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def alive(pid):
    """True while pid runs (a zombie, i.e. a crashed child not yet reaped, counts as gone)."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def cpu_seconds(pid):
    """User + system CPU time of pid (all threads), s; None when gone."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return None


def renice(pid, niceness):
    """Sets the nice value of every thread of pid (Linux keeps one per thread; new threads
    inherit their creator's). A diagnostic: does the nodelet keep up when it gets the CPU?"""
    try:
        tids = [int(t) for t in os.listdir("/proc/%d/task" % pid)]
    except OSError:
        return
    for tid in tids:
        try:
            os.setpriority(os.PRIO_PROCESS, tid, niceness)
        except OSError:
            pass


def cpu_times():
    """(busy, total) jiffies of the whole machine, from /proc/stat."""
    with open("/proc/stat") as f:
        values = [int(v) for v in f.readline().split()[1:]]
    idle = values[3] + (values[4] if len(values) > 4 else 0)  # idle + iowait
    return sum(values) - idle, sum(values)


def busy_percent(before, after):
    busy, total = after[0] - before[0], after[1] - before[1]
    return 100.0 * busy / total if total > 0 else 0.0


def load_average():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def machine_line():
    model = "unknown"
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True, check=False).stdout.strip()
    if subprocess.run(["git", "-C", ROOT, "status", "--porcelain"], capture_output=True,
                      text=True, check=False).stdout.strip():
        commit += "-dirty"
    return 'machine: nproc=%d cpu="%s" load=%s date=%s commit=%s' % (
        len(os.sched_getaffinity(0)), model, load_average(),
        datetime.datetime.now().astimezone().isoformat(timespec="seconds"), commit or "unknown")


def percentile(values, q):
    """Linear interpolation between order statistics (as scripts/bench and acvo_tum)."""
    if not values:
        return float("nan")
    v = sorted(values)
    pos = q * (len(v) - 1)
    lo = int(pos)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (pos - lo) * (v[hi] - v[lo])


def slope(xs, ys):
    """Least-squares slope of ys over xs (0 with fewer than two points)."""
    n = len(xs)
    if n < 2:
        return 0.0
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else 0.0


# ------------------------------------------------------------------------------------------
# The graph
# ------------------------------------------------------------------------------------------
class Rig:
    """roscore on a free port + roslaunch acvo acvo.launch; stop() ends both (by their pids)."""

    def __init__(self, env, log_dir, launch_args=(), wait_topics=()):
        self.env = dict(env)
        self.port = free_port()
        self.master_uri = "http://127.0.0.1:%d" % self.port
        self.env["ROS_MASTER_URI"] = self.master_uri
        self.env["ROS_LOG_DIR"] = os.path.join(log_dir, "ros_log")
        self.env.pop("ROS_HOSTNAME", None)
        self.env["ROS_IP"] = "127.0.0.1"
        self.log_dir = log_dir
        self.launch_args = list(launch_args)
        self.wait_topics = list(wait_topics)
        self.core = self.launch = None
        self.manager_pid = None
        os.makedirs(log_dir, exist_ok=True)
        self.launch_log = os.path.join(log_dir, "nodelet.log")

    def master(self):
        return xmlrpc.client.ServerProxy(self.master_uri)

    def start(self, timeout=60.0):
        """The master, then the nodelet."""
        self.start_master(timeout)
        return self.start_nodelet(timeout)

    def start_master(self, timeout=60.0):
        core_log = open(os.path.join(self.log_dir, "roscore.log"), "w")
        self.core = subprocess.Popen(["roscore", "-p", str(self.port)], env=self.env,
                                     stdout=core_log, stderr=subprocess.STDOUT,
                                     start_new_session=True)
        deadline = time.monotonic() + timeout
        while True:
            try:
                self.master().getPid("/rig")
                return self
            except OSError:
                if self.core.poll() is not None or time.monotonic() > deadline:
                    raise RigError("roscore on port %d did not start (see %s)" %
                                   (self.port, core_log.name))
                time.sleep(0.2)

    def start_nodelet(self, timeout=60.0, log_dir=None):
        """roslaunch acvo acvo.launch; returns once the manager subscribes to wait_topics."""
        if log_dir:
            os.makedirs(log_dir, exist_ok=True)
            self.launch_log = os.path.join(log_dir, "nodelet.log")
        launch_log = open(self.launch_log, "w")
        self.launch = subprocess.Popen(["roslaunch", "acvo", "acvo.launch"] + self.launch_args,
                                       env=self.env, stdout=launch_log,
                                       stderr=subprocess.STDOUT, start_new_session=True)
        self.manager_pid = self._wait_for_nodelet(time.monotonic() + timeout)
        return self

    def _wait_for_nodelet(self, deadline):
        """The manager's pid, once it subscribes to every topic of wait_topics."""
        while True:
            if self.launch.poll() is not None:
                raise RigError("roslaunch ended (exit %d), see %s" %
                               (self.launch.returncode, self.launch_log))
            try:
                _, _, state = self.master().getSystemState("/rig")
                subscribed = {topic for topic, nodes in state[1] if MANAGER in nodes}
                if all(t in subscribed for t in self.wait_topics):
                    _, _, uri = self.master().lookupNode("/rig", MANAGER)
                    _, _, pid = xmlrpc.client.ServerProxy(uri).getPid("/rig")
                    return int(pid)
            except OSError:
                pass
            if time.monotonic() > deadline:
                raise RigError("the nodelet did not subscribe to %s in time, see %s" %
                               (", ".join(self.wait_topics), self.launch_log))
            time.sleep(0.2)

    def stop_nodelet(self):
        self._end(self.launch)
        self.launch = None

    def stop(self):
        self._end(self.launch)
        self._end(self.core)
        self.launch = self.core = None

    @staticmethod
    def _end(proc):
        if proc is None or proc.poll() is not None:
            return
        proc.send_signal(signal.SIGINT)  # roslaunch and roscore shut their nodes down
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)  # its own session: only what it started
            proc.wait()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()
        return False


def warning_lines(log_path, limit=12):
    """The distinct WARN/ERROR lines of a launch log, most frequent first (with counts)."""
    counts = {}
    try:
        with open(log_path, errors="replace") as f:
            for line in f:
                if "[ WARN]" in line or "[ERROR]" in line:
                    # Drop the "[ WARN] [stamp]: " prefix so repeats of one message merge.
                    text = ANSI.sub("", line).split("]: ", 1)[-1].strip()
                    text = "".join(c if not c.isdigit() else "#" for c in text)[:160]
                    counts[text] = counts.get(text, 0) + 1
    except OSError:
        return []
    return sorted(counts.items(), key=lambda kv: -kv[1])[:limit]


# ------------------------------------------------------------------------------------------
# What comes back (rospy: call after apply_environment)
# ------------------------------------------------------------------------------------------
class Listener:
    """odom, odom_info and /diagnostics of the nodelet, keyed by stamp (ns)."""

    def __init__(self):
        import rospy
        from acvo.msg import OdometryInfo
        from diagnostic_msgs.msg import DiagnosticArray
        from nav_msgs.msg import Odometry
        self.lock = threading.Lock()
        self.reset()
        self.subs = [rospy.Subscriber("odom", Odometry, self.on_odom, queue_size=1000),
                     rospy.Subscriber("odom_info", OdometryInfo, self.on_info, queue_size=1000),
                     rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics,
                                      queue_size=10)]

    def reset(self):
        """Forgets what came so far (a new nodelet)."""
        with self.lock:
            self.odom = {}  # stamp ns -> receipt (monotonic s)
            self.odom_count = 0
            self.duplicate_odom = 0
            self.non_finite = []  # stamps whose pose was not finite
            self.info = {}  # stamp ns -> (tracking, ms_total, message)
            self.last_receipt = time.monotonic()
            self.diagnostics = {}

    def on_odom(self, msg):
        now = time.monotonic()
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        finite = all(math.isfinite(v) for v in (p.x, p.y, p.z, q.x, q.y, q.z, q.w))
        key = msg.header.stamp.to_nsec()
        with self.lock:
            self.odom_count += 1
            if key in self.odom:
                self.duplicate_odom += 1
            self.odom[key] = now
            if not finite:
                self.non_finite.append(key)
            self.last_receipt = now

    def on_info(self, msg):
        with self.lock:
            self.info[msg.header.stamp.to_nsec()] = (msg.tracking, msg.ms_total, msg.message)
            self.last_receipt = time.monotonic()

    def on_diagnostics(self, msg):
        for status in msg.status:
            values = {kv.key: kv.value for kv in status.values}
            if "frames processed" in values:
                with self.lock:
                    self.diagnostics = dict(values, level=status.level, summary=status.message)

    def wait_idle(self, idle=3.0, limit=20.0):
        """Returns once nothing came for `idle` s (or after `limit` s)."""
        start = time.monotonic()
        while time.monotonic() - start < limit:
            with self.lock:
                quiet = time.monotonic() - self.last_receipt
            if quiet > idle:
                return
            time.sleep(0.2)
