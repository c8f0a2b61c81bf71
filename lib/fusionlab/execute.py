"""Run a notebook top to bottom in a fresh kernel, as Restart & Run All does: how the course tests its notebooks.

This is :class:`nbclient.NotebookClient` with one change. nbclient waits for the kernel's replies with
``zmq.asyncio`` polls, and a zmq socket announces new messages on an edge-triggered file descriptor: on a loaded
machine a wake-up can be missed, and the poll then sleeps until its timeout -- the cell's whole time budget --
although the reply arrived long before. Seen here on a 2-core machine: Lab 02's widget cell (about twenty messages
at once) took exactly the 300 s timeout in three of four fresh-clone test runs, then passed; a two-cell notebook
beside three busy loops stalled in 5 of 8 runs, and in 0 of 8 with the polls below. Polling in short slices
bounds a missed wake-up to one slice (a poll that times out looks at the socket again).

    >>> import nbformat
    >>> nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1 + 1")])
    >>> run_notebook(nb).cells[0].outputs[0]["data"]["text/plain"]
    '2'
"""

from __future__ import annotations

import os
import time
from queue import Empty

import nbformat
from jupyter_client.asynchronous import AsyncKernelClient
from jupyter_client.channels import AsyncZMQSocketChannel
from jupyter_client.manager import AsyncKernelManager
from nbclient import NotebookClient
from traitlets import DottedObjectName, Type, default

__all__ = ["run_notebook", "NotebookRunner", "SLICE"]

SLICE = 0.25  # seconds: the longest a missed wake-up can delay a message


class _SlicedChannel(AsyncZMQSocketChannel):
    """A kernel channel whose wait for a message looks at the socket every :data:`SLICE` seconds."""

    async def get_msg(self, timeout=None):
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            wait = SLICE if deadline is None else min(SLICE, max(0.0, deadline - time.monotonic()))
            if await self.socket.poll(int(wait * 1000)):
                return await self._recv()
            if deadline is not None and time.monotonic() >= deadline:
                raise Empty


class _SlicedClient(AsyncKernelClient):
    """The asynchronous kernel client, with every socket channel sliced."""

    shell_channel_class = Type(_SlicedChannel)
    iopub_channel_class = Type(_SlicedChannel)
    stdin_channel_class = Type(_SlicedChannel)
    control_channel_class = Type(_SlicedChannel)


class _SlicedKernelManager(AsyncKernelManager):
    """The asynchronous kernel manager, handing out sliced clients."""

    client_class = DottedObjectName("fusionlab.execute._SlicedClient")
    client_factory = Type(klass=_SlicedClient)


class NotebookRunner(NotebookClient):
    """:class:`nbclient.NotebookClient` whose kernel client polls in slices (see the module's docstring).

    Parameters
    ----------
    nb : nbformat.NotebookNode
        The notebook to execute (its cells receive the outputs).
    km : jupyter_client.manager.AsyncKernelManager, optional
        A kernel manager to use instead of a new one (whose client then decides how it polls).
    **kw
        Every other option of :class:`nbclient.NotebookClient` (``timeout``, ``allow_errors``, ``resources``...).
    """

    @default("kernel_manager_class")
    def _default_kernel_manager_class(self):
        return _SlicedKernelManager


def run_notebook(
    nb: nbformat.NotebookNode | str | os.PathLike,
    cwd: str | os.PathLike | None = None,
    timeout: float = 300,
    allow_errors: bool = True,
    kernel_name: str = "python3",
    stderr=None,
) -> nbformat.NotebookNode:
    """Execute every cell of ``nb`` in a fresh kernel (kernel start included); return the notebook with outputs.

    Parameters
    ----------
    nb : nbformat.NotebookNode or path-like
        The notebook, or the path of an ``.ipynb`` file (read, never written back).
    cwd : path-like, optional
        The kernel's working folder; default the notebook file's folder, or the current folder for a
        notebook given in memory.
    timeout : float, optional
        Seconds one cell may take before it is stopped with an error.
    allow_errors : bool, optional
        Go on after a cell that raises (its error stays in its outputs), as Run All of an unfinished lab.
    kernel_name : str, optional
        The Jupyter kernel to start.
    stderr : optional
        Where the kernel process's own stderr goes (e.g. ``subprocess.DEVNULL``); default inherited.
    """
    if isinstance(nb, (str, os.PathLike)):
        path = os.fspath(nb)
        if not os.path.isfile(path):
            raise ValueError(f"nb must be a notebook or the path of an .ipynb file; {path!r} is not a file")
        cwd = os.path.dirname(os.path.abspath(path)) if cwd is None else cwd
        nb = nbformat.read(path, as_version=4)
    elif not isinstance(nb, nbformat.NotebookNode):
        raise ValueError(f"nb must be a notebook (nbformat.NotebookNode) or a path; got {type(nb).__name__}")
    if not (isinstance(timeout, (int, float)) and not isinstance(timeout, bool) and timeout > 0):
        raise ValueError(f"timeout must be a positive number of seconds; got {timeout!r}")
    cwd = os.fspath(cwd) if cwd is not None else os.getcwd()
    if not os.path.isdir(cwd):
        raise ValueError(f"cwd must be an existing folder; got {cwd!r}")
    runner = NotebookRunner(
        nb,
        timeout=timeout,
        kernel_name=kernel_name,
        allow_errors=bool(allow_errors),
        resources={"metadata": {"path": cwd}},
    )
    runner.execute(**({} if stderr is None else {"stderr": stderr}))
    return nb
