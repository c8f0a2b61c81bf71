"""What the integrity report (:mod:`grading.integrity`) flags, as data: each kind of flag with the sentence a reviewer
reads beside it, and the names, modules, calls and magics that raise each kind. What answers exercises (the packages
and names of the kind ``package``) is the table of exercises' (:mod:`fusionlab.checks.exercises`)."""
from __future__ import annotations

import re

from fusionlab.checks import exercises

# Names every lab binds in its locked setup cell (aliases of modules) even when the scanner cannot see an import.
MODULE_NAMES = {"np", "numpy", "plt", "matplotlib", "sp", "sympy", "scipy", "fusionlab", "builtins", "sys", "os",
                "math", "IPython", "filterpy", "guard", "checks"}

# kind -> why (one sentence a reviewer reads beside the offending line)
WHY = {
    "patch": "assigns or deletes an attribute of an imported module or object: it can change what the tests compare",
    "rebind": "rebinds a name the locked setup cell or the tests rely on",
    "reflection": "reflection (setattr/getattr/vars/globals, __code__, __dict__ ...) reaches code it should not touch",
    "builtins": "touches the builtins every cell (and every test) uses",
    "sys-hook": "changes interpreter machinery (sys.modules, sys.excepthook, settrace, import hooks, atexit)",
    "ipython": "reaches the IPython shell (get_ipython, input/AST transformers, set_custom_exc, event callbacks)",
    "exec": "runs code built at run time (exec, eval, compile, __import__, importlib)",
    "reference": "uses the reference function this exercise asks you to write yourself",
    "file": "writes a file, or reads the instructor's folders",
    "process": "starts a process or a shell command",
    "thread": "starts a thread or a timer that runs after the cell",
    "network": "opens a network connection",
    "ctypes": "calls native code (ctypes/cffi)",
    "signal": "installs a signal handler",
    "operator": "defines a class whose comparisons or conversions could fool an assert",
    "foreign-cell": "carries nbgrader metadata with a grade_id this lab does not have (pasted from another lab?)",
    "syntax": "does not parse as Python (scanned token by token instead)",
    "copied": "a function whose code has the shape of one in the library, names and comments aside (copied?)",
    "package": "uses a package whose functions answer exercises (ahrs, scipy's Rotation, filterpy's helpers)",
    "unreadable": "the submission is not a readable notebook",
    "loader": "loads a module or runs code by a name or a text built at run time (import tricks)",
}

DUNDERS = {"__code__", "__dict__", "__globals__", "__closure__", "__defaults__", "__kwdefaults__", "__subclasses__",
           "__bases__", "__mro__", "__loader__", "__spec__", "__func__", "__wrapped__", "__setattr__", "__delattr__",
           "__getattribute__", "__class__", "__self__", "__reduce__", "__reduce_ex__", "__subclasshook__",
           "__file__"}
CALLS = {  # bare names that are suspicious when called
    "setattr": "reflection", "delattr": "reflection", "getattr": "reflection", "vars": "reflection",
    "globals": "reflection", "locals": "reflection", "exec": "exec", "eval": "exec", "compile": "exec",
    "__import__": "exec", "get_ipython": "ipython", "breakpoint": "sys-hook",
}
IPYTHON_ATTRS = {"input_transformers_cleanup", "input_transformers_post", "input_transformer_manager",
                 "ast_transformers", "set_custom_exc", "custom_exceptions", "CustomTB", "register_magic_function",
                 "register_magics", "run_cell", "run_cell_magic", "run_line_magic", "showtraceback",
                 "_showtraceback", "showsyntaxerror", "InteractiveTB", "SyntaxTB", "user_ns", "user_global_ns",
                 "set_hook", "prefilter_manager", "display_pub", "transform_cell", "run_cell_async", "do_execute",
                 "dispatch_shell", "shell_handlers", "display_trap", "displayhook"}
SYS_ATTRS = {"modules", "path", "excepthook", "settrace", "setprofile", "meta_path", "path_hooks",
             "path_importer_cache", "displayhook", "unraisablehook", "addaudithook", "_getframe", "setrecursionlimit",
             "stdout", "stderr",
             "breakpointhook", "audit"}
MODULE_KINDS = {  # importing any of these (or a submodule) is flagged
    "builtins": "builtins", "ctypes": "ctypes", "cffi": "ctypes", "signal": "signal", "subprocess": "process",
    "multiprocessing": "process", "pty": "process", "socket": "network", "urllib": "network", "requests": "network",
    "http": "network", "httpx": "network", "ftplib": "network", "smtplib": "network", "urllib3": "network",
    "aiohttp": "network", "websocket": "network", "importlib": "exec", "runpy": "exec", "code": "exec",
    "codeop": "exec", "marshal": "exec", "types": "reflection", "inspect": "reflection", "gc": "reflection",
    "atexit": "sys-hook", "threading": "thread", "_thread": "thread", "sched": "thread", "asyncio": "thread",
    "shutil": "file", "tempfile": "file", "IPython": "ipython", "ipykernel": "ipython", "unittest": "reflection",
    "concurrent": "process",
    **{package: "package" for package in exercises.PACKAGES},   # packages whose functions answer exercises
}
# names that answer exercises (scipy's Rotation, ahrs's q_prod ...), from the table of exercises
ANSWERING_NAMES = {dotted.rsplit(".", 1)[-1]: "package" for dotted in exercises.ANSWERING}
OS_CALLS = {"system": "process", "popen": "process", "fork": "process", "forkpty": "process", "kill": "process",
            "killpg": "process", "spawnl": "process", "spawnv": "process", "spawnve": "process", "spawnlp": "process",
            "execv": "process", "execve": "process", "execl": "process", "execlp": "process", "execvp": "process",
            "posix_spawn": "process", "_exit": "process", "remove": "file", "unlink": "file", "rename": "file",
            "replace": "file", "rmdir": "file", "removedirs": "file", "makedirs": "file", "mkdir": "file",
            "chmod": "file", "chdir": "file", "symlink": "file", "link": "file", "truncate": "file",
            "putenv": "process", "environ": "process"}
WRITE_METHODS = {"write_text", "write_bytes", "savetxt", "savez", "savez_compressed", "tofile", "to_csv",
                 "to_excel", "to_pickle", "savefig", "touch", "mkdir", "unlink", "rmdir", "rename", "symlink_to",
                 "dump"}
OPERATOR_DUNDERS = {"__eq__", "__ne__", "__lt__", "__le__", "__gt__", "__ge__", "__bool__", "__array__",
                    "__array_ufunc__", "__array_function__", "__array_interface__", "__float__", "__complex__",
                    "__abs__", "__len__", "__index__", "__int__", "__getattr__"}
INSTRUCTOR_PATHS = re.compile(r"\.\.|^/|solution|gradebook|autograded|submitted|feedback|nbgrader_config")
# Harmless magics; any other magic is flagged (``!cmd`` and shell cell magics as processes).
SAFE_MAGICS = {"matplotlib", "timeit", "time", "precision", "pprint", "who", "whos", "pinfo", "pinfo2", "psearch"}
SHELL_MAGICS = {"system", "sx", "bash", "sh", "script", "perl", "ruby", "python", "python3", "pypy", "sc", "run",
                "load", "writefile", "env", "store", "cd", "pushd", "popd", "rm", "mkdir", "mv", "cp"}
