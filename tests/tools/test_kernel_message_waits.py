"""The kernels lorisnb starts (reports, the notebook tests) are read by a client whose waits for a
message look at the socket again every :data:`MESSAGE_LOOK_SECONDS`: a reply already on the socket
was once left unseen until the whole cell timeout (threshold_sensitivity's widget cell took 240.0 s,
papermill's whole timeout, in 2 of 7 runs under load; ``lorisnb report`` would wait 30 minutes)."""

from __future__ import annotations

import asyncio
import time
from queue import Empty

import pytest
from jupyter_client.channels import AsyncZMQSocketChannel

from lorisnb.tools.report import notebooks


@pytest.fixture
def channel(monkeypatch):
    """A waking channel over a socket that has a message only at the ``ready``-th look."""
    monkeypatch.setattr(notebooks, "MESSAGE_LOOK_SECONDS", 0.05)
    looks: list[float | None] = []
    state = {"ready": None}

    async def look(self, timeout=None):
        looks.append(timeout)
        if state["ready"] is not None and len(looks) >= state["ready"]:
            return {"msg_type": "execute_reply"}
        await asyncio.sleep(timeout or 0)
        raise Empty

    monkeypatch.setattr(AsyncZMQSocketChannel, "get_msg", look)
    client = notebooks.kernel_manager_class()(kernel_name="python3").client()
    return client.shell_channel_class.__new__(client.shell_channel_class), looks, state


def test_clients_of_lorisnb_kernels_use_waking_channels():
    client = notebooks.kernel_manager_class()(kernel_name="python3").client()
    for name in ("shell", "iopub", "stdin", "control"):
        assert issubclass(getattr(client, f"{name}_channel_class"), AsyncZMQSocketChannel)
        assert getattr(client, f"{name}_channel_class").__name__ == "WakingChannel", name


def test_a_wait_is_cut_into_looks_with_the_same_timeout(channel):
    ch, looks, _ = channel
    t = time.monotonic()
    with pytest.raises(Empty):
        asyncio.run(ch.get_msg(timeout=0.125))
    took = time.monotonic() - t
    assert 0.12 <= took < 1.0
    assert len(looks) >= 3 and all(x is not None and x <= 0.05 + 1e-9 for x in looks)
    assert sum(looks) == pytest.approx(0.125, abs=0.03)


def test_a_message_is_returned_at_the_look_that_finds_it(channel):
    ch, looks, state = channel
    state["ready"] = 3
    assert asyncio.run(ch.get_msg(timeout=10)) == {"msg_type": "execute_reply"}
    assert len(looks) == 3
    looks.clear()
    state["ready"] = 4  # no timeout: looks until a message comes, never Empty
    assert asyncio.run(ch.get_msg()) == {"msg_type": "execute_reply"} and len(looks) == 4
    looks.clear()
    state["ready"] = None
    with pytest.raises(Empty):  # timeout 0: one look, at once
        asyncio.run(ch.get_msg(timeout=0))
    assert looks == [0.0]
