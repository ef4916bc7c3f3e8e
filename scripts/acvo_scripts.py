"""What the scripts share (scripts/bench, bag_rate, soak_nodelet, window_errors, and the folder
tools depth_distortion, depth_noise, distort_tum, downsample_tum, register_colour).

  paths        the repository, the workspace, the built tools, the shared data sets
  build        scripts/build with its log, the path of a built tool
  datasets     a folder's associations, camera.yaml and depth images, TUM trajectories and their
               poses, synthetic sequences rendered once by acvo_synth, the real data sets, names
  statistics   percentile and slope (numpy)
  machine      the "machine:" line printed with every figure (nproc, CPU, load, date, commit)
  /proc        memory, CPU time and liveness of a process, the machine's CPU and load
  ROS graph    a master on a free port, launch/acvo.launch (its own nodelet manager), and a
               listener of what the nodelet publishes (Rig, Listener)

A script imports it from its own folder:

    sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
    import acvo_scripts as ac  # noqa: E402

Nothing here imports rospy, numpy or the message modules at import time: scripts/bench runs
without a ROS environment, and the nodelet scripts set the environment up first
(ros_environment, apply_environment), then use Listener or import rospy themselves.
tum_to_bag, record_trajectory and plot_trajectories.py do not import this module: catkin
installs them on their own.
"""
import datetime
import json
import math
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client

# ------------------------------------------------------------------------------------------
# Paths
# ------------------------------------------------------------------------------------------
ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
WS = os.environ.get("ACVO_WS", os.path.join(ROOT, "build", "ws"))
TOOLS = os.path.join(WS, "devel", "lib", "acvo")
BENCH_OUT = os.path.join(ROOT, "build", "bench")  # scripts/bench's outputs and synthetic sets
SHARED_DATA = os.path.join(ROOT, "..", "shared", "data")
TEDDY = os.path.join(SHARED_DATA, "tum_fr3_teddy200")
KITCHEN = os.path.join(SHARED_DATA, "kitchen7s_dev")
KITCHEN2 = os.path.join(SHARED_DATA, "kitchen7s_dev2")
MANAGER = "/acvo_manager"  # acvo.launch's manager for name:=acvo
ANSI = re.compile(r"\x1b\[[0-9;]*m")  # roscpp's colour codes in the launch log


class ScriptError(Exception):
    """A set-up failure (build, missing tool, a ROS graph that does not start): the scripts
    end with its message and exit status 2."""


def log(who, message):
    """A progress line on stderr, "<who>: message" (stdout holds the figures)."""
    print("%s: %s" % (who, message), file=sys.stderr, flush=True)


# ------------------------------------------------------------------------------------------
# Build, tools
# ------------------------------------------------------------------------------------------
def build(who, log_dir=BENCH_OUT):
    """scripts/build (ACVO_JOBS defaults to nproc - 1), its output in log_dir/build.log; raises
    ScriptError with the last lines of that file when it fails."""
    os.makedirs(log_dir, exist_ok=True)
    build_log = os.path.join(log_dir, "build.log")
    env = dict(os.environ)
    env.setdefault("ACVO_JOBS", str(max(1, len(os.sched_getaffinity(0)) - 1)))
    log(who, "building (log: %s)" % os.path.relpath(build_log, ROOT))
    start = time.monotonic()
    with open(build_log, "w") as f:
        rc = subprocess.run([os.path.join(ROOT, "scripts", "build")], stdout=f,
                            stderr=subprocess.STDOUT, env=env, check=False).returncode
    if rc != 0:
        with open(build_log) as f:
            sys.stderr.write("".join(f.readlines()[-30:]))
        raise ScriptError("build failed (exit %d), see %s" % (rc, build_log))
    log(who, "build ok (%.0f s)" % (time.monotonic() - start))


def tool(name):
    """The path of a built tool of build/ws (ACVO_WS); ScriptError when it is not built."""
    path = os.path.join(TOOLS, name)
    if not os.access(path, os.X_OK):
        raise ScriptError("%s is not built (looked in %s)" % (name, TOOLS))
    return path


def summary_figures(output):
    """The key=value figures of a tool's last output line (acvo_tum: frames= median_ms= ...;
    acvo_eval: rpe_trans_rmse= ...), as strings; {} for no output."""
    lines = output.strip().splitlines()
    return dict(re.findall(r"(\w+)=(\S+)", lines[-1])) if lines else {}


def write_json(path, data):
    """data as indented JSON (its folder made when missing), ending with a newline."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        json.dump(data, f, indent=2)
        f.write("\n")


# ------------------------------------------------------------------------------------------
# Datasets
# ------------------------------------------------------------------------------------------
def read_associations(folder):
    """(rgb stamp, rgb file, depth stamp, depth file) of each line of a folder's associations.txt,
    colour first whichever way the file lists them: depth first (ICL-NUIM's archives, TUM's
    associate.py given depth.txt first) is told by the folder the first file lies in, as acvo_tum
    and tum_to_bag tell it. OSError without the file, ValueError on a line of under 4 fields."""
    def in_depth(path):
        return os.path.basename(os.path.dirname(path)).startswith("depth")

    rows = []
    with open(os.path.join(folder, "associations.txt")) as f:
        for number, line in enumerate(f, 1):
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            if len(fields) < 4:
                raise ValueError("%s/associations.txt:%d: expected 'stamp file stamp file'"
                                 % (folder, number))
            first, second = tuple(fields[0:2]), tuple(fields[2:4])
            if in_depth(first[1]) and not in_depth(second[1]):
                first, second = second, first
            rows.append(first + second)
    return rows


def read_camera_yaml(folder):
    """A folder's camera.yaml as YAML reads it ({} when empty). OSError without the file,
    yaml.YAMLError where it is not YAML."""
    import yaml
    with open(os.path.join(folder, "camera.yaml")) as f:
        return yaml.safe_load(f) or {}


def intrinsic_matrix(camera):
    """The 3x3 intrinsic matrix of camera.yaml's fx, fy, cx and cy (KeyError without one)."""
    import numpy as np
    return np.array([[float(camera["fx"]), 0, float(camera["cx"])],
                     [0, float(camera["fy"]), float(camera["cy"])], [0, 0, 1.0]])


def depth_metres(raw, scale):
    """A 16-bit depth image in metres (float32), NaN where it holds no reading: 0, or 65535 as
    7-Scenes marks it (acvo's depthToMeters)."""
    import numpy as np
    depth = raw.astype(np.float32) / np.float32(scale)
    depth[(raw == 0) | (raw == 65535)] = np.nan
    return depth


def read_trajectory(path, offset=0.0):
    """A TUM trajectory file ("stamp tx ty tz qx qy qz qw" lines; further columns ignored) as an
    (n, 8) numpy array sorted by stamp, `offset` added to the stamps. ValueError on another
    layout, OSError without the file."""
    import numpy as np
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith('#'):
                rows.append([float(x) for x in line.split()[:8]])
    a = np.array(rows)
    if a.ndim != 2 or a.shape[1] != 8:
        raise ValueError('%s: expected lines "stamp tx ty tz qx qy qz qw"' % path)
    a[:, 0] += offset
    return a[np.argsort(a[:, 0])]


def pose_matrix(row):
    """The 4x4 transform of a trajectory row (stamp, translation, quaternion x y z w; the
    quaternion normalised)."""
    import numpy as np
    x, y, z, w = row[4:8] / np.linalg.norm(row[4:8])
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    T[:3, 3] = row[1:4]
    return T


def count_frames(folder):
    """Frames listed in a folder's associations.txt (0 when absent)."""
    try:
        return len(read_associations(folder))
    except (OSError, ValueError):
        return 0


def render_sequence(folder, frames, options, who):
    """acvo_synth FOLDER --frames N OPTIONS, again only when the folder is missing, shorter
    than `frames` or made with other options (kept in FOLDER/bench_options.txt). Rendered into
    FOLDER.partial first: an interrupted run leaves no half folder behind."""
    stamp = os.path.join(folder, "bench_options.txt")
    try:
        with open(stamp) as f:
            same_options = f.read().split() == options
    except OSError:
        same_options = False
    if same_options and count_frames(folder) >= frames:
        return folder
    log(who, "generating %s (%d frames)" % (os.path.relpath(folder, ROOT), frames))
    partial = folder + ".partial"
    shutil.rmtree(partial, ignore_errors=True)
    cmd = [tool("acvo_synth"), partial, "--frames", str(frames)] + options
    result = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise ScriptError("acvo_synth failed:\n" + result.stdout + result.stderr)
    with open(os.path.join(partial, "bench_options.txt"), "w") as f:
        f.write(" ".join(options) + "\n")
    shutil.rmtree(folder, ignore_errors=True)
    os.rename(partial, folder)
    return folder


def synthetic_dataset(structure, texture, frames, who="bench"):
    """build/bench/synth_<structure>_<texture>: one of the four TUM structure/texture
    conditions, 640x480, Kinect-like noise, 30 Hz, seed 1 (scripts/bench, scripts/bag_rate)."""
    options = ["--structure", structure, "--texture", texture, "--noise", "on", "--seed", "1",
               "--rate", "30", "--width", "640", "--height", "480"]
    return render_sequence(os.path.join(BENCH_OUT, "synth_%s_%s" % (structure, texture)),
                           frames, options, who)


def real_datasets(candidates=(TEDDY, KITCHEN, KITCHEN2)):
    """Those of the shared real data sets that are present, as real paths."""
    return [os.path.realpath(d) for d in candidates if os.path.isdir(d)]


def unique_names(folders):
    """A name per folder (its base name; _2, _3 ... for repeats)."""
    names, seen = [], {}
    for folder in folders:
        base = os.path.basename(os.path.normpath(folder)) or "dataset"
        seen[base] = seen.get(base, 0) + 1
        names.append(base if seen[base] == 1 else "%s_%d" % (base, seen[base]))
    return names


# ------------------------------------------------------------------------------------------
# Statistics
# ------------------------------------------------------------------------------------------
def percentile(values, q, empty=math.nan):
    """The q-quantile (q in [0, 1]) with linear interpolation between order statistics (numpy's
    default, as acvo_tum computes it); `empty` for no values."""
    if len(values) == 0:
        return empty
    import numpy as np
    return float(np.quantile(values, q))


def slope(xs, ys):
    """Least-squares slope of ys over xs (0 with fewer than two distinct xs)."""
    if len(set(xs)) < 2:
        return 0.0
    import numpy as np
    return float(np.polyfit(xs, ys, 1)[0])


# ------------------------------------------------------------------------------------------
# Machine
# ------------------------------------------------------------------------------------------
def git(*args):
    return subprocess.run(["git", "-C", ROOT] + list(args), capture_output=True, text=True,
                          check=False).stdout.strip()


def load_average():
    """The 1, 5 and 15-minute load averages, as /proc/loadavg writes them."""
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def machine_info(load_averages=1):
    """nproc, CPU model, load, date and commit (short hash, "-dirty" when the tree has
    changes besides the documents, *.md and docs/, which the figures do not depend on and the
    scripts write). load: the first `load_averages` of the 1, 5 and 15-minute figures (scripts/bench
    records the 1-minute one; the nodelet scripts, whose runs last minutes, all three)."""
    model = "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        load = " ".join(load_average().split()[:load_averages])
    except OSError:
        load = "?"
    commit = git("rev-parse", "--short", "HEAD") or "unknown"
    if git("status", "--porcelain", "--", ".", ":(exclude)*.md", ":(exclude)docs/"):
        commit += "-dirty"
    return {
        "nproc": len(os.sched_getaffinity(0)),
        "cpu": model,
        "load": load,
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "commit": commit,
    }


def machine_line(info):
    return 'machine: nproc=%d cpu="%s" load=%s date=%s commit=%s' % (
        info["nproc"], info["cpu"], info["load"], info["date"], info["commit"])


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


# ------------------------------------------------------------------------------------------
# ROS environment
# ------------------------------------------------------------------------------------------
def ros_environment(ws=WS):
    """os.environ as build/ws/devel/setup.bash leaves it (package path, message modules)."""
    setup = os.path.join(ws, "devel", "setup.bash")
    if not os.path.isfile(setup):
        raise ScriptError("%s is missing: build first (scripts/build)" % setup)
    out = subprocess.run(["bash", "-c", 'source "$0" && env -0', setup], capture_output=True,
                         check=True).stdout
    env = dict(item.split("=", 1) for item in out.decode().split("\0") if "=" in item)
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    return env


def apply_environment(env):
    """Makes this process see env (rospy reads ROS_MASTER_URI; acvo.msg needs PYTHONPATH)."""
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
                    raise ScriptError("roscore on port %d did not start (see %s)" %
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
                raise ScriptError("roslaunch ended (exit %d), see %s" %
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
                raise ScriptError("the nodelet did not subscribe to %s in time, see %s" %
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
