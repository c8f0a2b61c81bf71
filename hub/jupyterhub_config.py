"""JupyterHub configuration of the course's hub: ``make hub`` (``python -m hub.run``) starts it with this file.

It reads what ``make hub`` prepared (accounts, folders, passwords, the API token) from ``$FUSIONLAB_HUB_DIR/hub.json``
and sets up

* the hub on http://127.0.0.1:PORT only (a shared password logs in: for one machine, never for a network);
* the proxy installed by ``make hub`` from the npm registry into ``hub/node_modules`` (pinned in hub/package.json);
* one JupyterLab per account as that account's Unix user (:class:`hub.spawner.CourseSpawner`): the instructor's on
  the instructor's copy of the course with Formgrader, each student's on their home with the student view; memory
  and CPU limits per server;
* the idle culler (``jupyterhub-idle-culler``): a server idle for ``idle_seconds`` is stopped;
* a service token (``course-admin``) that scripts and the course's tests use to start servers and call them.
"""

import json
import os
import sys

c = get_config()  # noqa: F821 (provided by JupyterHub)

HERE = os.path.dirname(os.path.abspath(__file__))
if os.path.dirname(HERE) not in sys.path:  # the repository: `hub.spawner` imports from there
    sys.path.insert(0, os.path.dirname(HERE))
STATE = os.environ["FUSIONLAB_HUB_DIR"]
with open(os.path.join(STATE, "hub.json")) as fh:
    s = json.load(fh)

c.JupyterHub.bind_url = f"http://127.0.0.1:{s['port']}/"
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = s["hub_port"]
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{s['proxy_api_port']}"
c.JupyterHub.db_url = f"sqlite:///{STATE}/jupyterhub.sqlite"
c.JupyterHub.cookie_secret_file = os.path.join(STATE, "jupyterhub_cookie_secret")
c.JupyterHub.cleanup_servers = True  # the servers stop with the hub (Ctrl-C leaves none)
c.ConfigurableHTTPProxy.command = [os.path.join(HERE, "node_modules", ".bin", "configurable-http-proxy")]
c.ConfigurableHTTPProxy.pid_file = os.path.join(STATE, "proxy.pid")

c.JupyterHub.authenticator_class = "shared-password"
c.SharedPasswordAuthenticator.user_password = s["student_password"]
c.SharedPasswordAuthenticator.admin_password = s["instructor_password"]
c.Authenticator.allowed_users = set(s["students"])
c.Authenticator.admin_users = {s["instructor"]}

c.JupyterHub.spawner_class = "hub.spawner.CourseSpawner"
c.CourseSpawner.instructor = s["instructor"]
c.CourseSpawner.course = s["course"]
c.CourseSpawner.venv = s["venv"]
c.CourseSpawner.instructor_config = os.path.join(STATE, "config", "instructor")
c.CourseSpawner.student_config = os.path.join(STATE, "config", "student")
c.CourseSpawner.student_view = s["student_view"]
c.CourseSpawner.instructor_settings = s["instructor_settings"]
c.CourseSpawner.student_settings = s["student_settings"]
c.Spawner.cmd = [os.path.join(s["venv"], "bin", "jupyterhub-singleuser")]
c.Spawner.default_url = "/lab"
c.Spawner.mem_limit = s["memory_mb"] * 2**20 if s["memory_mb"] else None
c.Spawner.cpu_limit = s["cpus"] or None
c.Spawner.start_timeout = 120
c.Spawner.http_timeout = 90

python = os.path.join(s["venv"], "bin", "python")
c.JupyterHub.services = [
    {"name": "idle-culler", "command": [python, "-m", "jupyterhub_idle_culler", f"--timeout={s['idle_seconds']}"]},
    {"name": "course-admin", "api_token": s["api_token"]},
]
c.JupyterHub.load_roles = [
    {
        "name": "idle-culler",
        "services": ["idle-culler"],
        "scopes": ["list:users", "read:users:activity", "read:servers", "delete:servers"],
    },
    {
        "name": "course-admin",
        "services": ["course-admin"],
        "scopes": ["admin:users", "admin:servers", "access:servers", "list:users", "read:users"],
    },
]
