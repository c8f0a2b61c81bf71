"""``fusionlab.execute``: a notebook run top to bottom in a fresh kernel, with polls that cannot sleep through a
reply."""

from __future__ import annotations

import asyncio
import time
from queue import Empty

import nbformat
import pytest
import zmq
import zmq.asyncio
from jupyter_client.session import Session

from fusionlab import execute


def _nb(*sources):
    return nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(s) for s in sources])


def test_every_cell_runs_and_an_error_stays_in_its_cell():
    nb = execute.run_notebook(_nb("x = 20 + 1", "1 / 0", "print(x * 2)"), timeout=60)
    assert nb.cells[1].outputs[0]["ename"] == "ZeroDivisionError"
    assert nb.cells[2].outputs[0]["text"] == "42\n"


def test_the_kernel_runs_in_the_notebooks_folder(tmp_path):
    path = tmp_path / "here.ipynb"
    nbformat.write(_nb("import os; print(os.getcwd())"), path)
    nb = execute.run_notebook(path, timeout=60)
    assert nb.cells[0].outputs[0]["text"].strip() == str(tmp_path)
    assert nbformat.read(path, as_version=4).cells[0].outputs == []  # the file is never written back


def test_the_runner_waits_with_sliced_polls():
    runner = execute.NotebookRunner(_nb("1"), kernel_name="python3")
    client_class = runner.create_kernel_manager().client_factory
    assert client_class is execute._SlicedClient
    for channel in ("shell", "iopub", "stdin", "control"):
        assert getattr(client_class, f"{channel}_channel_class").default_value is execute._SlicedChannel


def _pair():
    ctx = zmq.asyncio.Context()
    a, b = ctx.socket(zmq.PAIR), ctx.socket(zmq.PAIR)
    port = a.bind_to_random_port("tcp://127.0.0.1")
    b.connect(f"tcp://127.0.0.1:{port}")
    return ctx, a, b


def test_a_sliced_wait_gives_up_at_its_timeout_and_not_before():
    async def wait():
        ctx, a, b = _pair()
        channel = execute._SlicedChannel(b, Session())
        start = time.monotonic()
        with pytest.raises(Empty):
            await channel.get_msg(timeout=0.6)
        took = time.monotonic() - start
        a.close(0), b.close(0), ctx.term()
        return took

    took = asyncio.run(wait())
    assert 0.6 <= took < 0.6 + 2 * execute.SLICE + 0.5


def test_a_message_sent_during_a_long_wait_is_received_within_a_slice():
    async def wait():
        ctx, a, b = _pair()
        session = Session()
        channel = execute._SlicedChannel(b, session)

        async def send_later():
            await asyncio.sleep(0.3)
            session.send(a, "execute_reply", {"status": "ok"})

        sender = asyncio.ensure_future(send_later())
        start = time.monotonic()
        msg = await channel.get_msg(timeout=30)
        took = time.monotonic() - start
        await sender
        a.close(0), b.close(0), ctx.term()
        return msg, took

    msg, took = asyncio.run(wait())
    assert msg["msg_type"] == "execute_reply" and msg["content"] == {"status": "ok"}
    assert took < 0.3 + execute.SLICE + 1.0


@pytest.mark.parametrize(
    "bad, message",
    [
        ({"nb": "no/such/notebook.ipynb"}, "nb must be a notebook or the path of an .ipynb file"),
        ({"nb": {"cells": []}}, "nb must be a notebook (nbformat.NotebookNode) or a path; got dict"),
        ({"timeout": 0}, "timeout must be a positive number of seconds; got 0"),
        ({"timeout": True}, "timeout must be a positive number of seconds; got True"),
        ({"cwd": "no/such/folder"}, "cwd must be an existing folder"),
    ],
)
def test_bad_arguments_are_named(bad, message):
    args = {"nb": _nb("1"), **bad}
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        execute.run_notebook(**args)
