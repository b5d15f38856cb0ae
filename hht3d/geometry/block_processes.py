"""Child processes that build the blocks of a large surface's robust Laplacian side by side (issue 39).

``robust_laplacian`` holds the GIL while it builds, so threads would build one block at a
time: the 256 blocks of a 10M-point cloud took 623 s on one core of two.  The blocks are
independent (:mod:`.blocks`), so :func:`mapped` hands them to :func:`process_count` child
processes, each building one block at a time (about 0.5 GB each at :data:`~.blocks.CLOUD_BLOCK`).

A child is a Python interpreter running :func:`serve`, with the parent's ``sys.path``: it
reads pickled ``(function, arguments)`` from its stdin and writes the pickled result, or the
exception, to a copy of its stdout, whose descriptor then points at stderr, so that native
output cannot corrupt the stream.  Each message is framed (:data:`_MAGIC`, its length): a
stream that is corrupted anyway raises an error instead of waiting.  Not ``multiprocessing``:
spawning imports the caller's script again (a script without a main guard would run twice)
and forking copies a multi-threaded process.  A child ignores SIGINT and ends at the end of
its stdin: when its parent has no more work, or has ended (then after its block at most); a
parent that stops kills its children.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import queue
import signal
import struct
import subprocess
import sys
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import IO, Any

from ..errors import InputError
from ..linalg.threads import SINGLE_THREAD_ENV

__all__ = ["PROCESSES_ENV", "process_count", "mapped", "serve"]

#: Environment variable: how many child processes build blocks (``1``: this process builds them).
PROCESSES_ENV = "HHT3D_BLOCK_PROCESSES"
#: Seconds a child whose stream ended is given to exit, before it is taken as alive with a corrupt stream.
_ENDING = 10.0
#: The first bytes of every message, before its length (8 bytes, little-endian).
_MAGIC = b"hht3d-block"


def process_count() -> int:
    """Child processes for blocks: :data:`PROCESSES_ENV` if set, else the cores this process may use.

    Raises
    ------
    InputError
        When :data:`PROCESSES_ENV` is not a positive integer.
    """
    value = os.environ.get(PROCESSES_ENV)
    if value is None:
        return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    try:
        count = int(value)
    except ValueError:
        count = 0
    if count < 1:
        raise InputError(f"{PROCESSES_ENV}={value!r}: expected a positive integer (1 builds blocks in this process)")
    return count


def mapped(function: Callable[..., Any], arguments: Iterable[tuple], processes: int) -> Iterator[Any]:
    """``function(*args)`` for each ``args`` of ``arguments``, in order.

    With ``processes`` > 1 the calls run in that many children (module notes), at most
    ``2 * processes`` of them prepared ahead of the results read; ``function`` and the
    arguments must pickle (a module-level function, arrays).  A call's exception is raised
    here; a child that ends without an answer raises :class:`RuntimeError` with its exit code.
    """
    if processes <= 1:
        yield from (function(*args) for args in arguments)
        return
    children = [_Child() for _ in range(processes)]
    idle: queue.SimpleQueue[_Child] = queue.SimpleQueue()
    for child in children:
        idle.put(child)

    def call(args: tuple) -> Any:
        child = idle.get()
        try:
            return child.call(function, args)
        finally:
            idle.put(child)

    pool = ThreadPoolExecutor(processes, thread_name_prefix="hht3d-blocks")
    try:
        pending: deque = deque()
        for args in arguments:
            pending.append(pool.submit(call, args))
            if len(pending) >= 2 * processes:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
    finally:
        for child in children:
            child.end()
        pool.shutdown(cancel_futures=True)


class _Child:
    """One child process and its two pipes."""

    def __init__(self) -> None:
        path = os.pathsep.join(entry for entry in sys.path if entry)
        self.process = subprocess.Popen(
            [sys.executable, "-c", f"from {__name__} import serve; serve()"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env={**os.environ, **SINGLE_THREAD_ENV, "PYTHONPATH": path},  # the children share the cores already
        )

    def call(self, function: Callable[..., Any], args: tuple) -> Any:
        stdin, stdout = self.process.stdin, self.process.stdout
        assert stdin is not None and stdout is not None
        try:
            _send(stdin, pickle.dumps((function, args), protocol=pickle.HIGHEST_PROTOCOL))
            failed, value = pickle.loads(_received(stdout))
        except (EOFError, OSError) as error:
            raise RuntimeError(f"a process building the Laplacian's blocks {self._fate(error)}") from error
        if failed:
            raise value
        return value

    def _fate(self, error: Exception) -> str:
        """What happened to a child whose stream failed with ``error``: ended (its code), or corrupt (ended here)."""
        try:
            code = self.process.wait(timeout=_ENDING)
        except subprocess.TimeoutExpired:
            self.end()
            return f"sent a corrupt answer and was ended: {error}"
        return f"ended with code {code}" + (" (killed: out of memory?)" if code == -9 else "")  # -9: SIGKILL

    def end(self) -> None:
        """Stop the child, whatever it is doing: it holds nothing to save."""
        self.process.kill()
        self.process.wait()
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None:
                with contextlib.suppress(OSError):  # a request left unsent to a child that has ended
                    stream.close()


def serve() -> None:
    """A child's work (module notes): ignore SIGINT, move native output to stderr, answer on stdout."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    answers = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    _answered(sys.stdin.buffer, answers)


def _answered(requests: IO[bytes], answers: IO[bytes]) -> None:
    """Answer each pickled ``(function, args)`` with ``(failed, result or exception)``, to the end of ``requests``."""
    while True:
        try:
            function, args = pickle.loads(_received(requests))
        except EOFError:
            return
        try:
            answer = (False, function(*args))
        except Exception as error:  # sent to the parent, which raises it
            answer = (True, error)
        try:
            data = pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as error:  # an exception or result that does not pickle
            data = pickle.dumps((True, RuntimeError(repr(error))), protocol=pickle.HIGHEST_PROTOCOL)
        _send(answers, data)


def _send(stream: IO[bytes], data: bytes) -> None:
    stream.write(_MAGIC + struct.pack("<Q", len(data)) + data)
    stream.flush()


def _received(stream: IO[bytes]) -> bytes:
    """The next message's bytes; :class:`EOFError` at the end of the stream, :class:`OSError` if it is corrupt."""
    head = stream.read(len(_MAGIC) + 8)
    if not head:
        raise EOFError
    if len(head) < len(_MAGIC) + 8 or not head.startswith(_MAGIC):
        raise OSError(f"corrupt message from a block process: {head[:40]!r}")
    (size,) = struct.unpack("<Q", head[len(_MAGIC) :])
    data = stream.read(size)
    if len(data) < size:
        raise EOFError
    return data
