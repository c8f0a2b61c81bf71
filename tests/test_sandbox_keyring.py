"""No box reaches the kernel's key store (``grading.sandbox.keyring_filter``, installed by ``INSIDE``).

Keyrings belong to a user id, not to a process tree, and outlive the processes that fill them: every box of one slot
runs as one user, so a key stored by one box (a capstone filter's look-ahead result) could be read back by the next
box of that slot (the "fresh" boxes of the causality check, or the next student graded in the slot). In every box
``add_key``, ``request_key`` and ``keyctl`` fail with EPERM, and nothing else is refused.

The first tests check the BPF program itself with a small interpreter of the few instructions it uses; the others
start real boxes, as grading does, and check the errno each call gets. Each test that starts a box first shows that
the kernel here does give keys to a process outside a box: otherwise an EPERM inside proves nothing.
"""
from __future__ import annotations

import json
import os
import shutil
import struct
import subprocess
import sys
import textwrap
import uuid

import pytest

from conftest import ROOT
from grading import sandbox

LAB = "02_kalman_falling_body"
NEEDS_BWRAP = pytest.mark.skipif(not shutil.which("bwrap"), reason="needs bubblewrap (apt-get install bubblewrap)")
EPERM, ENOKEY = 1, 126
ALLOW, REFUSE = 0x7FFF0000, 0x00050000 | EPERM          # SECCOMP_RET_ALLOW, SECCOMP_RET_ERRNO | EPERM
X86_64, AARCH64, I386 = 0xC000003E, 0xC00000B7, 0x40000003
KEY_CALLS = {"x86_64": (248, 249, 250), "aarch64": (217, 218, 219)}   # add_key, request_key, keyctl

# What a box runs to call the key store: each call's result and errno, as JSON on the last line.
PROBE = textwrap.dedent("""
    import ctypes, json, os, sys
    libc = ctypes.CDLL(None, use_errno=True)
    ADD_KEY, REQUEST_KEY, KEYCTL = {"x86_64": (248, 249, 250), "aarch64": (217, 218, 219)}[os.uname().machine]
    KEY_SPEC_PROCESS_KEYRING, KEY_SPEC_SESSION_KEYRING, KEY_SPEC_USER_KEYRING = -2, -3, -4
    KEYCTL_GET_KEYRING_ID, KEYCTL_REVOKE, KEYCTL_UNLINK = 0, 3, 9
    KEYCTL_SEARCH, KEYCTL_READ, KEYCTL_SET_TIMEOUT = 10, 11, 15
    L = ctypes.c_long

    def call(nr, *args):
        ctypes.set_errno(0)
        result = libc.syscall(L(nr), *(L(a) if isinstance(a, int) else a for a in args))
        return [result, ctypes.get_errno() if result == -1 else 0]
""")


def _run_probe(code, **box):
    """``PROBE`` + ``code`` outside any box (``box`` empty) or in a box (``box``: tmp_path, slot); its JSON line."""
    source = PROBE + textwrap.dedent(code)
    if not box:
        run = subprocess.run([sys.executable, "-c", source], capture_output=True, text=True, timeout=60)
    else:
        run = _in_box(source, **box)
    assert run.returncode == 0, f"the probe should run to its end: {run.stderr[-2000:]}"
    return json.loads(run.stdout.strip().splitlines()[-1])


def _in_box(source, tmp_path, slot):
    """Run ``python -c source`` in a box started the way grading starts one, as the user of ``slot``."""
    course = tmp_path / "course"
    (course / "lib").mkdir(parents=True, exist_ok=True)
    (course / "labs" / LAB).mkdir(parents=True, exist_ok=True)
    uid = sandbox.box_uid(slot)
    work = sandbox.private_folder(None, tmp_path, uid)
    command = sandbox.bwrap_command(["python", "-c", source], course=course, lab=LAB, lib=course / "lib", work=work,
                                    uid=uid, data=False)
    return subprocess.run(command, capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)


def _keys_work_outside_a_box():
    """Skip unless a process outside any box can use the key store (its own process keyring: nothing outlives it)."""
    got = _run_probe("""
        kid = call(ADD_KEY, b"user", b"fusionlab-outside", b"data", 4, KEY_SPEC_PROCESS_KEYRING)
        print(json.dumps({"add_key": kid}))
    """)
    if got["add_key"][0] <= 0:
        pytest.skip(f"the kernel here refuses the key store to every process (add_key: errno {got['add_key'][1]}): "
                    f"a refusal inside a box would prove nothing")


@pytest.fixture
def slot():
    with sandbox.claimed_slots(1) as [mine]:
        yield mine


# ---------------------------------------------------------------------------------------------------------------
# The BPF program
# ---------------------------------------------------------------------------------------------------------------

def _verdict(program, arch, nr):
    """What the kernel would do with a call (``arch``, ``nr``): the filter's return value. Interprets only the
    instructions a seccomp filter like ours needs; any other fails the test."""
    data = struct.pack("=iI", nr, arch) + bytes(56)           # struct seccomp_data: nr, arch, ip, args
    insns = [struct.unpack("=HBBI", program[i:i + 8]) for i in range(0, len(program), 8)]
    pc, acc = 0, 0
    for _ in range(len(insns)):                              # no loops in classic BPF: each instruction once at most
        code, jt, jf, k = insns[pc]
        if code == 0x20:                                     # BPF_LD | BPF_W | BPF_ABS
            acc = struct.unpack_from("=I", data, k)[0]
            pc += 1
        elif code in (0x15, 0x25, 0x35):                     # BPF_JMP | JEQ / JGT / JGE, against k
            taken = {0x15: acc == k, 0x25: acc > k, 0x35: acc >= k}[code]
            pc += 1 + (jt if taken else jf)
        elif code == 0x06:                                   # BPF_RET | BPF_K
            return k
        else:
            raise AssertionError(f"expected only loads, jumps and returns in the filter, got code {code:#x} at {pc}")
    raise AssertionError("expected the filter to end in a return")


def test_the_filter_refuses_the_three_key_calls_and_allows_the_rest_on_x86_64():
    program = sandbox.keyring_filter("x86_64")
    assert len(program) % 8 == 0 and 6 * 8 <= len(program) <= 12 * 8, len(program)
    assert struct.unpack("=HBBI", program[:8]) == (0x20, 0, 0, 4), "the first instruction loads the arch"
    for nr in KEY_CALLS["x86_64"]:
        assert _verdict(program, X86_64, nr) == REFUSE, nr
    for nr in (0, 1, 2, 9, 56, 57, 59, 60, 202, 231, 247, 251, 317, 435):   # read, write, mmap, clone, fork, futex...
        assert _verdict(program, X86_64, nr) == ALLOW, nr
    for nr in (248, 249, 250, 0, 1, 60):                      # the x32 ABI: same arch, number + 0x40000000
        assert _verdict(program, X86_64, 0x40000000 | nr) == REFUSE, nr
    for nr in (0, 3, 4, 286, 287, 288):                       # i386 through int 0x80 (286-288: its key calls)
        assert _verdict(program, I386, nr) == REFUSE, nr


def test_the_filter_refuses_the_three_key_calls_and_allows_the_rest_on_aarch64():
    program = sandbox.keyring_filter("aarch64")
    for nr in KEY_CALLS["aarch64"]:
        assert _verdict(program, AARCH64, nr) == REFUSE, nr
    for nr in (56, 63, 64, 93, 98, 172, 216, 220, 221, 222, 248, 249, 250):  # openat, read, write, exit, futex...
        assert _verdict(program, AARCH64, nr) == ALLOW, nr
    assert _verdict(program, X86_64, 0) == REFUSE and _verdict(program, 0x40000028, 3) == REFUSE, \
        "a call of any other arch (here x86_64's, and 32-bit arm's) is refused"


def test_a_machine_without_a_filter_is_refused_by_name_and_stops_grading(monkeypatch):
    for machine in ("riscv64", "i686", "aarch64_be", "x86_64 (a 32-bit Python)"):
        with pytest.raises(sandbox.UnsupportedMachine, match=r"expected a machine of x86_64 or aarch64, this one is"):
            sandbox.keyring_filter(machine)
    monkeypatch.setattr(sandbox, "_native_machine", lambda: "riscv64")
    with pytest.raises(sandbox.UnsupportedMachine, match="riscv64"):
        sandbox.bwrap_command(["python", "box.py"], course=ROOT, lab=LAB, lib=ROOT / "lib", work=str(ROOT))
    said = sandbox.box_problem(str(ROOT), LAB, "/nonexistent", [0])
    assert said.startswith("grading cannot be made safe on this machine (expected a machine of x86_64 or aarch64, "
                           "this one is riscv64"), said
    assert "never run without that filter" in said and "Where to grade" in said, said


def test_the_box_is_handed_this_machines_filter(tmp_path):
    work = sandbox.private_folder(None, tmp_path)
    args = sandbox.bwrap_command(["python", "box.py"], course=tmp_path, lab=LAB, lib=tmp_path, work=work)
    env = {args[i + 1]: args[i + 2] for i, a in enumerate(args) if a == "--setenv"}
    assert bytes.fromhex(env["FUSIONLAB_BOX_SECCOMP"]) == sandbox.keyring_filter(os.uname().machine)


# ---------------------------------------------------------------------------------------------------------------
# Real boxes
# ---------------------------------------------------------------------------------------------------------------

@NEEDS_BWRAP
def test_each_key_call_in_a_box_fails_with_eperm(tmp_path, slot):
    _keys_work_outside_a_box()
    got = _run_probe("""
        print(json.dumps({
            "add_key process": call(ADD_KEY, b"user", b"desc", b"data", 4, KEY_SPEC_PROCESS_KEYRING),
            "add_key session": call(ADD_KEY, b"user", b"desc", b"data", 4, KEY_SPEC_SESSION_KEYRING),
            "add_key user": call(ADD_KEY, b"user", b"desc", b"data", 4, KEY_SPEC_USER_KEYRING),
            "request_key": call(REQUEST_KEY, b"user", b"desc", None, 0),
            "keyctl get_keyring_id": call(KEYCTL, KEYCTL_GET_KEYRING_ID, KEY_SPEC_USER_KEYRING, 1),
            "keyctl search": call(KEYCTL, KEYCTL_SEARCH, KEY_SPEC_SESSION_KEYRING, b"user", b"desc", 0),
        }))
    """, tmp_path=tmp_path, slot=slot)
    assert got == {name: [-1, EPERM] for name in got} and len(got) == 6, got


@NEEDS_BWRAP
def test_a_secret_stored_by_one_box_is_not_found_by_the_next_box_of_the_slot(tmp_path, slot, monkeypatch):
    """The attack: the first box stores a look-ahead result in its user's keyring (and in the session keyring it
    inherits), the second box of the same slot looks for it. First without the filter, where it must work (as root,
    where both boxes are one user of the machine's own), then with it."""
    desc = f"fusionlab-lookahead-{uuid.uuid4().hex}".encode()

    def store(keyrings):
        return f"""
            desc, secret, stored = {desc!r}, b"x_hat[k+1] = 4.2", {{}}
            for name in {keyrings!r}:
                kid = call(ADD_KEY, b"user", desc, secret, len(secret), globals()[f"KEY_SPEC_{{name}}_KEYRING"])
                if kid[0] > 0:
                    call(KEYCTL, KEYCTL_SET_TIMEOUT, kid[0], 60)     # a key a failing test leaves behind expires
                stored[name] = kid
            print(json.dumps(stored))
        """
    look = f"""
        desc, found = {desc!r}, {{}}
        for name, kid in (("request_key", call(REQUEST_KEY, b"user", desc, None, 0)),
                          ("search", call(KEYCTL, KEYCTL_SEARCH, KEY_SPEC_USER_KEYRING, b"user", desc, 0))):
            secret = ""
            if kid[0] > 0:
                buf = ctypes.create_string_buffer(64)
                n = call(KEYCTL, KEYCTL_READ, kid[0], buf, 64)[0]
                secret = buf.raw[:max(n, 0)].decode()
            found[name] = kid + [secret]
        for kid, _, _ in found.values():                         # the key found goes: it would outlive the test
            if kid > 0:
                call(KEYCTL, KEYCTL_REVOKE, kid)
                call(KEYCTL, KEYCTL_UNLINK, kid, KEY_SPEC_USER_KEYRING)
        print(json.dumps(found))
    """
    if os.geteuid() == 0:                                    # the channel is real here: no filter, no refusal
        _keys_work_outside_a_box()
        with monkeypatch.context() as m:
            m.setattr(sandbox, "keyring_filter", lambda: struct.pack("=HBBI", 0x06, 0, 0, ALLOW))
            stored = _run_probe(store(["USER"]), tmp_path=tmp_path, slot=slot)
            assert stored["USER"][0] > 0, f"without the filter the first box stores its key: {stored}"
            found = _run_probe(look, tmp_path=tmp_path, slot=slot)
        assert found["request_key"][2] == found["search"][2] == "x_hat[k+1] = 4.2", \
            f"without the filter the second box reads it: {found}"

    stored = _run_probe(store(["USER", "SESSION"]), tmp_path=tmp_path, slot=slot)
    assert stored == {"USER": [-1, EPERM], "SESSION": [-1, EPERM]}, stored
    found = _run_probe(look, tmp_path=tmp_path, slot=slot)
    assert found == {"request_key": [-1, EPERM, ""], "search": [-1, EPERM, ""]}, found
    outside = _run_probe(f"print(json.dumps(call(KEYCTL, KEYCTL_SEARCH, KEY_SPEC_SESSION_KEYRING, b'user', {desc!r}, "
                         f"0)))")
    assert outside == [-1, ENOKEY], f"nothing reached the grader's session keyring either: {outside}"


@NEEDS_BWRAP
def test_an_ordinary_workload_runs_in_the_box(tmp_path, slot):
    """numpy, a thread, a fork and a child process: the filter refuses nothing else, and is in place."""
    got = _run_probe("""
        import subprocess, threading
        import numpy as np
        a = np.random.default_rng(7).standard_normal((120, 120))
        x = float(np.linalg.solve(a @ a.T + np.eye(120), np.ones(120)).sum())
        box = {}
        t = threading.Thread(target=lambda: box.update(thread=sum(range(1000))))
        t.start()
        t.join()
        pid = os.fork()
        if pid == 0:
            os._exit(7)
        fork = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
        child = subprocess.run([sys.executable, "-c", "print(6 * 7)"], capture_output=True, text=True).stdout.strip()
        status = dict(line.split(":", 1) for line in open("/proc/self/status") if ":" in line)
        print(json.dumps({"x": x, "thread": box.get("thread"), "fork": fork, "child": child,
                          "seccomp": status["Seccomp"].strip(), "env": "FUSIONLAB_BOX_SECCOMP" in os.environ,
                          "uid": os.getuid()}))
    """, tmp_path=tmp_path, slot=slot)
    import numpy as np
    a = np.random.default_rng(7).standard_normal((120, 120))
    x = float(np.linalg.solve(a @ a.T + np.eye(120), np.ones(120)).sum())
    assert got["x"] == pytest.approx(x, rel=1e-9), got
    assert (got["thread"], got["fork"], got["child"]) == (499500, 7, "42"), got
    assert got["seccomp"] == "2", f"a seccomp filter is installed in the box (mode 2): {got}"
    assert got["env"] is False, "INSIDE takes the filter out of the environment"
    if os.geteuid() == 0:
        assert got["uid"] == sandbox.box_uid(slot), got


@NEEDS_BWRAP
def test_a_box_that_cannot_install_its_filter_runs_nothing_and_is_reported(tmp_path, slot, monkeypatch):
    """A program the kernel refuses (it does not end in a return): INSIDE stops before the student's code."""
    monkeypatch.setattr(sandbox, "keyring_filter", lambda: struct.pack("=HBBI", 0x20, 0, 0, 4))
    run = _in_box("print('student code ran')", tmp_path=tmp_path, slot=slot)
    assert run.returncode != 0 and "student code ran" not in run.stdout, run.stdout
    assert "could not install its seccomp filter (prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER) failed: Invalid " \
           "argument)" in run.stderr, run.stderr
    said = sandbox.box_problem(str(ROOT), "01_euler_rotations", str(tmp_path), [slot])
    assert said.startswith("a test box did not start (the box could not install its seccomp filter"), said
    assert "no student code runs without it" in said, said
