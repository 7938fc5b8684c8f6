#!/usr/bin/env python3
"""Benchmark: PX4 lock-step exchanges per second between the simulator node and the stand-in
autopilot (test/scripts/px4_standin.py), at the 250 Hz sensor rate, without cameras.

Starts its own roscore and the simulator node (~autopilot px4, unpaced), flies the stand-in's
mission (arm, climb to 10 m, hold HOLD_S sim seconds, land) and prints the lock-step exchanges
(one HIL_SENSOR answered by one HIL_ACTUATOR_CONTROLS) per wall second, the real-time factor,
the wall round trip per exchange and the CPU seconds of the simulator and of the stand-in.
Run after sourcing build/devel/setup.bash:
  python3 bench/bench_sitl.py [HOLD_S]
"""
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "test", "scripts"))
import px4_standin  # noqa: E402
from graph_util import free_port, start_master, stop_master, stop_process  # noqa: E402


def main():
    hold = float(sys.argv[1]) if len(sys.argv) > 1 else 60.0
    master = free_port()
    os.environ["ROS_MASTER_URI"] = "http://localhost:%d" % master
    core = start_master(master)
    port = free_port()
    log = "/tmp/bench_sitl_simulator.log"
    scenario = os.path.join(HERE, "..", "scenarios", "default", "sim_config.json")
    sim = subprocess.Popen(
        ["rosrun", "hameritt", "simulator", "_sim_config:=" + scenario, "_cameras:=false",
         "_autopilot:=px4", "_px4_port:=%d" % port, "_real_time_factor:=0",
         "_duration:=100000"], stdout=open(log, "w"), stderr=subprocess.STDOUT)
    try:
        deadline = time.time() + 60
        while "waiting for PX4" not in open(log).read():
            if time.time() > deadline:
                raise RuntimeError("the simulator did not open its PX4 port; see " + log)
            time.sleep(0.1)
        ap = px4_standin.Autopilot(port, hold_s=hold, log=lambda m: None)
        cpu0 = time.process_time()
        wall0 = time.time()
        end = ap.run(max_wall_s=600)
        wall = time.time() - wall0
        cpu = time.process_time() - cpu0
        ap.close()
        sim_s = (ap.last_t - ap.first_t) * 1e-6
        print("flight: %s, %.1f sim s, %d exchanges in %.2f wall s" % (
            "landed" if ap.done else "NOT landed", sim_s, ap.sensors, wall))
        print("exchanges per wall second: %.0f; real-time factor %.1fx; round trip %.0f us per "
              "exchange (simulator + stand-in)" % (ap.sensors / wall, sim_s / wall,
                                                   1e6 * wall / ap.sensors))
        print("stand-in CPU: %.2f s (%.0f us per exchange)" % (cpu, 1e6 * cpu / ap.sensors))
    finally:
        stop_process(sim)
        stop_master(core)
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    print("simulator + roscore CPU: %.2f s user, %.2f s sys" % (ru.ru_utime, ru.ru_stime))


if __name__ == "__main__":
    main()
