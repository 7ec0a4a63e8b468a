#!/usr/bin/python3
"""Headless "display" for LinuxCNC (the INI's [DISPLAY]DISPLAY): machine on,
home, run [DISPLAY]OPEN_FILE to the end, print what truecut_comp did, exit
(LinuxCNC then shuts down). Exit status 0 when the program ran to the end
without an error message, 1 otherwise.

    linuxcnc xyzac-trt-truecut.ini
"""
import os
import sys
import time
import traceback

import hal
import linuxcnc

TIMEOUT_S = 120.0  # for the whole program; a stuck machine fails


def main():
    ini_path = sys.argv[sys.argv.index("-ini") + 1]
    ini = linuxcnc.ini(ini_path)
    program = os.path.join(os.path.dirname(os.path.abspath(ini_path)), ini.find("DISPLAY", "OPEN_FILE"))
    stat, command, errors = linuxcnc.stat(), linuxcnc.command(), linuxcnc.error_channel()
    watcher = hal.component("run-program")  # hal.get_value() needs a component
    watcher.ready()
    deadline = time.monotonic() + TIMEOUT_S
    problems = []

    def poll():
        stat.poll()
        e = errors.poll()
        if e:
            kind, text = e
            if kind in (linuxcnc.NML_ERROR, linuxcnc.OPERATOR_ERROR):
                problems.append(text)
            print("linuxcnc: " + text, flush=True)
        if time.monotonic() > deadline:
            raise RuntimeError("timed out")

    def wait_until(condition):
        while True:
            poll()
            if condition():
                return
            time.sleep(0.01)

    command.state(linuxcnc.STATE_ESTOP_RESET)
    command.state(linuxcnc.STATE_ON)
    wait_until(lambda: stat.task_state == linuxcnc.STATE_ON)
    command.mode(linuxcnc.MODE_MANUAL)
    command.home(-1)
    wait_until(lambda: all(stat.homed[j] for j in range(stat.joints)))
    command.mode(linuxcnc.MODE_AUTO)
    wait_until(lambda: stat.task_mode == linuxcnc.MODE_AUTO)
    command.program_open(program)
    command.auto(linuxcnc.AUTO_RUN, 0)
    wait_until(lambda: stat.interp_state != linuxcnc.INTERP_IDLE)
    # The external-offsets route ([TRUECUT]EOFFSET_AXES): the offsets motion
    # applies, against the component's correction.
    eoffset_axes = (ini.find("TRUECUT", "EOFFSET_AXES") or "").lower().split()
    max_eoffset = {a: 0.0 for a in eoffset_axes}
    max_corr = 0.0
    max_ferror = 0.0
    faults = set()
    while True:
        poll()
        max_corr = max(max_corr, hal.get_value("tc.corr-mag"))
        max_ferror = max([max_ferror] + [abs(hal.get_value("joint.%d.f-error" % j)) for j in range(3)])
        for a in eoffset_axes:
            max_eoffset[a] = max(max_eoffset[a], abs(hal.get_value("axis.%s.eoffset" % a)))
        faults.add(hal.get_value("tc.fault"))
        if stat.interp_state == linuxcnc.INTERP_IDLE:
            break
        time.sleep(0.005)
    # To the end: the interpreter went idle with no error, and the machine
    # stands where the program's last move left it ([TRUECUT]END_POSITION).
    # stat.position: X Y Z A B C U V W, external offsets included.
    end = {w[0].upper(): float(w[1:]) for w in (ini.find("TRUECUT", "END_POSITION") or "").split()}

    def programmed(a):
        p = stat.position["XYZABCUVW".index(a)]
        return p - hal.get_value("axis.%s.eoffset" % a.lower()) if a.lower() in eoffset_axes else p

    at_end = all(abs(programmed(a) - v) < 1e-6 for a, v in end.items())
    finished = not problems and stat.state != linuxcnc.RCS_ERROR and at_end
    print("program %s: %s at line %d (%s)" % (
        program, "finished" if finished else "failed", stat.motion_line,
        " ".join("%s%.6f" % (a, programmed(a)) for a in "XYZAC")))
    print("truecut_comp: field-generation %d, load-errors %d, max corr-mag %.6f mm, faults seen %s"
          % (hal.get_value("tc.field-generation"), hal.get_value("tc.load-errors"), max_corr,
             sorted(faults)))
    print("motion: max |f-error| of X, Y, Z %.6f mm" % max_ferror, flush=True)
    if eoffset_axes:
        # Standing at the end: the offset has caught up with its request.
        settle_deadline = time.monotonic() + 5.0
        while time.monotonic() < settle_deadline and any(
                abs(hal.get_value("axis.%s.eoffset" % a) - hal.get_value("axis.%s.eoffset-request" % a)) > 1e-12
                for a in eoffset_axes):
            time.sleep(0.01)
        print("external offsets: max |eoffset| %s mm; standing at the end, eoffset - corr %s mm" % (
            " ".join("%s %.6f" % (a.upper(), max_eoffset[a]) for a in eoffset_axes),
            " ".join("%s %.7f" % (a.upper(), hal.get_value("axis.%s.eoffset" % a) -
                                  hal.get_value("tc.corr-%s" % a)) for a in eoffset_axes)), flush=True)
    command.state(linuxcnc.STATE_OFF)
    return 0 if finished else 1


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Exception:  # noqa: BLE001 - report and fail
        traceback.print_exc()
        sys.stdout.flush()
        sys.exit(1)
