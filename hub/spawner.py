"""The hub's spawner: each account's JupyterLab as a local process of its own user, with its own view and limits.

:class:`CourseSpawner` is JupyterHub's ``LocalProcessSpawner`` (a server is a process of the account's Unix user)
with what the course adds:

* the instructor's server starts on (and in: its terminals open there) the instructor's copy of the course, with
  every nbgrader tool (Formgrader, Create Assignment, Course List), nbgrader configured for the exchange
  (``CourseDirectory.root`` set) and no Jupyter news pop-up (the settings of ``jupyter/lab/settings``);
* a student's server starts on the student's home folder with the student view of ``make lab`` (the repository's
  ``jupyter/`` folder: only the *Assignments* panel and **Validate** of nbgrader) and the exchange;
* memory and CPU are limited per server (``Spawner.mem_limit``, ``Spawner.cpu_limit``) by a control group of its
  own, which the server's process joins before it becomes the user (:class:`Limits`). ``LocalProcessSpawner``
  itself limits nothing; where control groups cannot be written, the hub says so in its log and runs without.

The paths are this class's settings, which ``hub/jupyterhub_config.py`` sets from what ``make hub`` (:mod:`hub.run`)
prepared.
"""

from __future__ import annotations

import os

from jupyterhub.spawner import LocalProcessSpawner
from traitlets import Unicode

ROOT = "/sys/fs/cgroup"


class Limits:
    """A control group per server, holding its memory (bytes) and CPU (cores) limits; cgroup v2 or v1."""

    def __init__(self, name, memory_bytes=None, cpus=None):
        self.name, self.memory_bytes, self.cpus = name, memory_bytes, cpus
        self.folders = []

    @staticmethod
    def _own(controller):
        """The control group this process is in, for a v1 ``controller`` ('' for v2)."""
        with open("/proc/self/cgroup") as fh:
            for line in fh:
                _, names, path = line.rstrip("\n").split(":", 2)
                if names.split(",") == [controller] or (controller == "" and names == ""):
                    return path
        return None

    def _v2(self):
        base = os.path.join(ROOT, self._own("").lstrip("/"))
        if not os.path.isfile(os.path.join(ROOT, "cgroup.controllers")):
            return None
        folder = os.path.join(base, "fusionlab-hub", self.name)
        os.makedirs(folder, exist_ok=True)
        with open(os.path.join(base, "fusionlab-hub", "cgroup.subtree_control"), "w") as fh:
            fh.write("+memory +cpu")
        if self.memory_bytes:
            with open(os.path.join(folder, "memory.max"), "w") as fh:
                fh.write(str(int(self.memory_bytes)))
        if self.cpus:
            with open(os.path.join(folder, "cpu.max"), "w") as fh:
                fh.write(f"{int(self.cpus * 100_000)} 100000")
        return [folder]

    def _v1(self):
        folders = []
        for controller, files in (
            ("memory", {"memory.limit_in_bytes": self.memory_bytes}),
            (
                "cpu",
                {"cpu.cfs_period_us": 100_000, "cpu.cfs_quota_us": int(self.cpus * 100_000) if self.cpus else None},
            ),
        ):
            own = self._own(controller)
            if own is None or not any(files.values()):
                continue
            folder = os.path.join(ROOT, controller, own.lstrip("/"), "fusionlab-hub", self.name)
            os.makedirs(folder, exist_ok=True)
            for name, value in files.items():
                if value:
                    with open(os.path.join(folder, name), "w") as fh:
                        fh.write(str(value))
            folders.append(folder)
        return folders

    def make(self):
        """Create the group(s) with their limits; return what was made, or raise OSError."""
        self.folders = self._v2() or self._v1()
        return self.folders

    def join(self, pid=0):
        """Put ``pid`` (0: this process) into the group(s); called in the child before it becomes the user."""
        for folder in self.folders:
            with open(os.path.join(folder, "cgroup.procs"), "w") as fh:
                fh.write(str(pid or os.getpid()))

    def remove(self):
        for folder in self.folders:
            try:
                os.rmdir(folder)
            except OSError:
                pass

    @staticmethod
    def remove_all(names):
        """Remove the groups of these accounts wherever they are (a server whose start failed leaves its own)."""
        import glob

        for pattern in ("fusionlab-hub", "*/fusionlab-hub", "*/**/fusionlab-hub"):
            for parent in glob.glob(os.path.join(ROOT, pattern), recursive=True):
                for name in names:
                    try:
                        os.rmdir(os.path.join(parent, name))
                    except OSError:
                        pass
                try:
                    os.rmdir(parent)
                except OSError:
                    pass


class CourseSpawner(LocalProcessSpawner):
    """LocalProcessSpawner with the course's two views, the exchange and per-server limits (module docstring)."""

    instructor = Unicode(help="the instructor's account: the one server with nbgrader's instructor tools").tag(
        config=True
    )
    course = Unicode(help="the instructor's copy of the course (its nbgrader_config.py): that server's root").tag(
        config=True
    )
    venv = Unicode(help="the course's environment: its bin goes first on every server's PATH").tag(config=True)
    instructor_config = Unicode(
        help="a folder with the instructor's nbgrader_config.py (exchange, course id, course root)"
    ).tag(config=True)
    student_config = Unicode(help="a folder with the students' nbgrader_config.py (exchange, course id)").tag(
        config=True
    )
    instructor_settings = Unicode(
        help="the instructor's JupyterLab settings (the repository's jupyter/lab/settings: "
        "no news pop-up, no update check)"
    ).tag(config=True)
    student_view = Unicode(help="the student view's configuration folder (the repository's jupyter/)").tag(config=True)
    student_settings = Unicode(
        help="the students' JupyterLab settings: the student view's (jupyter/lab/settings) "
        "and a menu that opens the Assignments panel"
    ).tag(config=True)

    def get_env(self):
        env = super().get_env()
        env["PATH"] = f"{self.venv}/bin:/usr/local/bin:/usr/bin:/bin"
        if self.user.name == self.instructor:
            env["JUPYTER_CONFIG_PATH"] = self.instructor_config
        else:
            env["JUPYTER_CONFIG_PATH"] = os.pathsep.join([self.student_view, self.student_config])
        return env

    def get_args(self):
        if self.user.name == self.instructor:
            self.notebook_dir = self.course
            self.args = [f"--LabApp.app_settings_dir={self.instructor_settings}"] if self.instructor_settings else []
        else:
            self.notebook_dir = "~"
            self.args = [f"--LabApp.app_settings_dir={self.student_settings}"]
        return super().get_args()

    def make_preexec_fn(self, name):
        become = super().make_preexec_fn(name)
        limits = getattr(self, "_limits", None)
        # LocalProcessSpawner starts every server in its user's home, and a terminal opened from JupyterLab's menu
        # (or its launcher at the top folder) opens where the server runs: the instructor's would open in ~, where
        # `python -m grading.classgrade` finds no `grading`. So the instructor's server runs in the course.
        folder = self.course if name == self.instructor and self.course else None

        def preexec():
            if limits is not None:
                limits.join()
            become()
            if folder:
                os.chdir(folder)

        return preexec

    async def start(self):
        self._limits = None
        if self.mem_limit or self.cpu_limit:
            limits = Limits(self.user.name, self.mem_limit, self.cpu_limit)
            try:
                limits.make()
                self._limits = limits
                self.log.info("%s: limits %s", self.user.name, ", ".join(limits.folders))
            except OSError as exc:
                self.log.warning(
                    "%s: memory and CPU limits are not enforced here (control groups: %s)", self.user.name, exc
                )
        return await super().start()

    async def stop(self, now=False):
        try:
            return await super().stop(now=now)
        finally:
            if getattr(self, "_limits", None) is not None:
                self._limits.remove()
