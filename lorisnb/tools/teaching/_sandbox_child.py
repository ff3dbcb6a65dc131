"""The process that runs a student's code inside the grading sandbox (started by
:mod:`lorisnb.tools.teaching.sandbox`; never imported by lorisnb, and it imports nothing of lorisnb).

It reads one JSON request a line from stdin and writes one JSON reply a line to the stdout it was
started with; the student's own prints go to ``student-output.txt`` in the working folder.

- ``{"op": "exec", "source": ..., "capture": [names]}``: run one cell in the notebook's namespace,
  then reply with each captured name's value as a plain value (number, bool, string; anything else
  is reported by its type only, never converted, so an object cannot wait to see the reference);
- ``{"op": "call", "name": ..., "args": {...}}``: call a function the cells defined and reply with
  its result as plain values (numbers or booleans, scalars or arrays).

With ``--no-lorisnb`` lorisnb cannot be imported (formula answers are graded with numpy alone).
Whatever the student's code does to this process can only change the replies about its own
answers: the references it is compared with are computed by the grader, in another process.
"""

from __future__ import annotations

import json
import os
import sys
import traceback
from typing import Any


def _plain(value: Any) -> Any:
    """A JSON-able description of an answer value (exact types only: no subclass, no proxy)."""
    import numpy as np

    t = type(value)
    if value is Ellipsis:
        return {"missing": True}
    if t in (bool, int, float, str) or value is None:
        return {"value": value}
    if isinstance(value, np.generic) and t.__module__ == "numpy" and value.dtype.kind in "biuf":
        return {"value": value.item()}
    pd = sys.modules.get("pandas")
    if pd is not None and t in (pd.Series, pd.DataFrame, pd.Index):  # pandas' own types (no subclass): their numbers
        value, t = value.to_numpy(), np.ndarray
    if t is np.ndarray and value.dtype.kind in "biuf":
        return {"array": value.tolist(), "dtype": value.dtype.str}
    return {"not_plain": f"{t.__module__}.{t.__qualname__}"}


def _decode(arg: Any) -> Any:
    import numpy as np

    if isinstance(arg, dict) and "array" in arg:
        return np.array(arg["array"], dtype=arg["dtype"])
    if isinstance(arg, dict) and "scalar" in arg:
        return np.dtype(arg["dtype"]).type(arg["scalar"])
    return arg


def main() -> None:
    no_lorisnb = "--no-lorisnb" in sys.argv
    reply = os.fdopen(os.dup(1), "w", encoding="utf-8")
    requests = os.fdopen(os.dup(0), "r", encoding="utf-8")
    log = os.open("student-output.txt", os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.dup2(log, 1)
    os.dup2(log, 2)
    sys.stdin = open(0, encoding="utf-8", closefd=False)  # noqa: SIM115 (the process's own stdin)
    if no_lorisnb:
        for name in [m for m in sys.modules if m == "lorisnb" or m.startswith("lorisnb.")]:
            del sys.modules[name]
        sys.modules["lorisnb"] = None  # type: ignore[assignment]  # import lorisnb -> ImportError
    else:
        import matplotlib

        matplotlib.use("Agg")  # figures are drawn, never shown
    namespace: dict[str, Any] = {"__name__": "__main__"}
    for line in requests:
        req = json.loads(line)
        request_id = req.pop("id", None)
        out: dict[str, Any] = {"ok": True}
        try:
            if req["op"] == "exec":
                exec(compile(req["source"], req.get("name", "<cell>"), "exec"), namespace)  # noqa: S102
            else:
                fn = namespace.get(req["name"])
                if not callable(fn):
                    raise NameError(f"{req['name']} is not defined (or not a function)")
                out["result"] = _plain(fn(**{k: _decode(v) for k, v in req["args"].items()}))
        except BaseException as exc:  # the student's code failed (or called exit()): its error is the reply
            out = {"ok": False, "error": f"{type(exc).__name__}: {exc}"[:2000]}
            traceback.print_exc()
        if req["op"] == "exec":
            out["values"] = {n: (_plain(namespace[n]) if n in namespace else {"missing": True}) for n in req["capture"]}
        sys.stdout.flush()
        out["id"] = request_id
        reply.write(json.dumps(out, default=str) + "\n")
        reply.flush()


if __name__ == "__main__":
    main()
