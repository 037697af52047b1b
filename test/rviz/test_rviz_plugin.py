#!/usr/bin/env python3
"""Smoke test of the rviz display stereo_fusion/Mesh in a real rviz on a virtual X screen.

rviz loads rviz/stereo_fusion.rviz (whose mesh display is the plugin) against a private master
on a free port, where this script plays the robot: it serves ~get_full_mesh and publishes
~mesh_update. Passes when rviz subscribed to ~mesh_update, fetched the full mesh when it
started, stayed in sync with the next update (no second fetch), fetched again after a gap in
the sequence (so the updates went through the display's tf filter and its bookkeeping), is
still running, and its log names no plugin that failed to load.

Exit 77 (ctest: Skipped, counted by scripts/test.sh) with the reason when rviz or Xvfb is not
installed or no X server can be started; never a silent pass.
    test_rviz_plugin.py RVIZ_CONFIG LOG_DIR
"""
import os
import shutil
import signal
import socket
import subprocess
import sys
import time

SKIP = 77


def skip(reason):
    print(f"SKIPPED: {reason}")
    sys.exit(SKIP)


def fail(reason, log_path=None):
    print(f"FAILED: {reason}")
    if log_path and os.path.exists(log_path):
        print(f"--- {log_path} (last 40 lines) ---")
        with open(log_path, errors="replace") as f:
            print("".join(f.readlines()[-40:]))
    sys.exit(1)


def wait_for(predicate, timeout_s, period_s=0.2):
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(period_s)
    return predicate()


def free_port():
    s = socket.socket()
    s.bind(("", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def descendant_named(root_pid, name):
    """The PID of a process called `name` below `root_pid` (from /proc), or None."""
    children = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            with open(f"/proc/{entry}/comm") as f:
                comm = f.read().strip()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append((int(entry), comm))
    todo = [root_pid]
    while todo:
        for pid, comm in children.get(todo.pop(), []):
            if comm == name:
                return pid
            todo.append(pid)
    return None


def stop(process):
    """SIGINT, then SIGKILL, to the process group this script started (xvfb-run and its
    children, or roscore and its children)."""
    if process.poll() is None:
        try:
            os.killpg(process.pid, signal.SIGINT)
            process.wait(timeout=10)
        except (subprocess.TimeoutExpired, ProcessLookupError):
            try:
                os.killpg(process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            process.wait()


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        return 2
    config, log_dir = sys.argv[1], sys.argv[2]
    for tool, package in (("rviz", "rviz"), ("xvfb-run", "xvfb"), ("xauth", "xauth")):
        if shutil.which(tool) is None:
            skip(f"'{tool}' is not installed (apt-get install {package}; scripts/setup.sh installs it)")
    os.makedirs(log_dir, exist_ok=True)
    os.environ.setdefault("ROS_HOSTNAME", "localhost")
    port = free_port()
    os.environ["ROS_MASTER_URI"] = f"http://localhost:{port}"

    master = subprocess.Popen(["roscore", "-p", str(port)], stdout=open(os.path.join(log_dir, "roscore.log"), "w"),
                              stderr=subprocess.STDOUT, start_new_session=True)
    rviz = None
    try:
        import rosgraph
        if not wait_for(rosgraph.is_master_online, 20):
            fail("the ROS master did not come up", os.path.join(log_dir, "roscore.log"))
        import rospy
        from geometry_msgs.msg import TransformStamped
        from stereo_fusion.msg import MeshBlock, MeshUpdate
        from stereo_fusion.srv import GetFullMesh, GetFullMeshResponse
        from tf2_msgs.msg import TFMessage

        rospy.init_node("rviz_plugin_smoke_test", disable_signals=True)
        session = 7

        def block(x, tag):
            b = MeshBlock()
            b.key = [x, 0, 0]
            b.vertices = [0.16 * x, 0.0, 0.0, 0.16 * x + 0.16, 0.0, 0.0, 0.16 * x, 0.16, 0.0]
            b.normals = [0.0, 0.0, 1.0] * 3
            b.colors = bytes([tag, 100, 50] * 3)
            b.triangles = [0, 1, 2]
            return b

        def mesh_update(sequence, blocks, full=False):
            u = MeshUpdate()
            u.header.frame_id = "map"
            u.header.stamp = rospy.Time.now()
            u.sequence, u.session, u.full = sequence, session, full
            u.voxel_size, u.block_size = 0.02, 0.16
            u.blocks = blocks
            return u

        calls = []

        def serve_full_mesh(_):
            calls.append(time.monotonic())
            return GetFullMeshResponse(mesh=mesh_update(1, [block(0, 200)], full=True))

        rospy.Service("/stereo_fusion/get_full_mesh", GetFullMesh, serve_full_mesh)
        updates = rospy.Publisher("/stereo_fusion/mesh_update", MeshUpdate, queue_size=10)
        tf_static = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = "map", "camera"
        t.transform.rotation.w = 1.0
        tf_static.publish(TFMessage([t]))

        rviz_log = os.path.join(log_dir, "rviz.log")
        env = dict(os.environ, LIBGL_ALWAYS_SOFTWARE="1")
        rviz = subprocess.Popen(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", "rviz", "-d", config],
                                stdout=open(rviz_log, "w"), stderr=subprocess.STDOUT, env=env,
                                start_new_session=True)

        def read_log():
            with open(rviz_log, errors="replace") as f:
                return f.read()

        def rviz_subscribed():
            if rviz.poll() is not None:
                return True  # ended: reported below
            _, subscribers, _ = rosgraph.Master("/rviz_plugin_smoke_test").getSystemState()
            return any(topic == "/stereo_fusion/mesh_update" and any(n.startswith("/rviz") for n in nodes)
                       for topic, nodes in subscribers)

        wait_for(rviz_subscribed, 90)
        if rviz.poll() is not None:
            text = read_log()
            if "Xvfb failed to start" in text or "cannot open display" in text.lower():
                skip(f"no X server could be started under xvfb-run (see {rviz_log})")
            fail(f"rviz ended with exit code {rviz.returncode} before subscribing", rviz_log)
        if not rviz_subscribed():
            fail("rviz did not subscribe to /stereo_fusion/mesh_update within 90 s: the display "
                 "stereo_fusion/Mesh was not loaded", rviz_log)
        if not wait_for(lambda: len(calls) >= 1, 30):
            fail("the display did not fetch /stereo_fusion/get_full_mesh after it started", rviz_log)
        if not wait_for(lambda: updates.get_num_connections() > 0, 10):
            fail("rviz's subscription to ~mesh_update never connected", rviz_log)

        updates.publish(mesh_update(2, [block(1, 120)]))  # the next after the full mesh (1)
        time.sleep(5.0)  # beyond the display's 2 s retry: a needless fetch would show
        if len(calls) != 1:
            fail(f"update 2 follows the full mesh at 1, yet the display fetched {len(calls)} times", rviz_log)
        updates.publish(mesh_update(5, [block(2, 60)]))  # 3 and 4 lost
        if not wait_for(lambda: len(calls) >= 2, 20):
            fail("after a gap in the sequence (2 -> 5) the display did not fetch the full mesh again", rviz_log)
        time.sleep(2.0)
        if rviz.poll() is not None:
            fail(f"rviz ended (exit code {rviz.returncode}) after drawing the mesh", rviz_log)
        text = read_log()
        for bad in ("could not be loaded", "Failed to load library", "PluginlibFactory", "Segmentation fault"):
            if bad in text:
                fail(f"rviz's log says '{bad}'", rviz_log)
        # Shutting down destroys the display with blocks drawn: rviz must end cleanly. SIGINT to
        # rviz itself (xvfb-run's child, which this script started): xvfb-run returns its status.
        rviz_pid = descendant_named(rviz.pid, "rviz")
        if rviz_pid is None:
            fail("rviz's process was not found under xvfb-run", rviz_log)
        os.kill(rviz_pid, signal.SIGINT)
        try:
            code = rviz.wait(timeout=20)
        except subprocess.TimeoutExpired:
            fail("rviz did not end within 20 s of SIGINT", rviz_log)
        if code != 0:
            fail(f"rviz ended with exit code {code} on SIGINT (a crash while destroying the display?)", rviz_log)
        print(f"rviz loaded stereo_fusion/Mesh: subscribed, fetched the full mesh at start and after "
              f"the gap ({len(calls)} fetches), drew, and ended cleanly")
        return 0
    finally:
        if rviz is not None:
            stop(rviz)
        stop(master)


if __name__ == "__main__":
    sys.exit(main())
