"""Where jobs run: long-lived local worker processes, or a Dask cluster."""

from __future__ import annotations

import gc
import logging
import multiprocessing
import os
import signal
import socket
import sys
import time
import uuid
from collections import deque
from collections.abc import Callable, Generator, Iterator, Sequence
from contextlib import contextmanager, suppress
from dataclasses import replace
from multiprocessing import forkserver
from multiprocessing.connection import wait
from typing import Any, Protocol
from urllib.parse import urlsplit

from vtrack.batch.jobs import Job, Outcome, Progress
from vtrack.batch.worker import _serve, execute_on_dask, stop_signal_name
from vtrack.errors import Interrupted, VtrackError, quoted
from vtrack.run import STATUS_FAILED

#: How often a job whose worker process died is started again before it is reported failed.
RETRIES = 1
#: How often a Dask batch checks that the scheduler still has a worker (seconds).
WORKER_POLL_S = 1.0
#: How long a stopped batch waits for its running jobs to finish (seconds).
STOP_GRACE_S = 5.0
#: How long a job still running then has, after SIGTERM, to end ``interrupted`` and write its
#: records, before its worker is killed (seconds).
RECORD_GRACE_S = 10.0
#: The Dask protocols ``--scheduler`` connects with: the others need what vtrack does not
#: give a Client (``tls``/``wss``: certificates; ``ucx``: UCX-Py and its network) or cannot
#: reach another process at all (``inproc``).
SCHEDULER_PROTOCOLS = ("tcp", "ws")
#: How long each connected worker has, at most, to say which vtrack it imports before a Dask
#: batch sends any job (seconds; the worker timeout when shorter).
ASK_WORKER_S = 30.0


class _StopSignal:
    """The signal an executor stops its running jobs with: ``signum`` until an
    :class:`Interrupted` passes out of :meth:`watch`, then the signal the batch got (their
    records name it)."""

    def __init__(self, signum: signal.Signals) -> None:
        self.signum = signum

    @contextmanager
    def watch(self) -> Iterator[None]:
        try:
            yield
        except Interrupted as exc:
            self.signum = signal.Signals(exc.signum)
            raise


class Executor(Protocol):
    """Runs jobs somewhere and yields one outcome per job, in completion order."""

    def run(self, jobs: Sequence[Job]) -> Generator[Outcome, None, None]: ...


def _died(job: Job, how: str) -> Outcome:
    times = "once" if job.attempt == 1 else f"{job.attempt} times"
    return Outcome(job.input, job.config, STATUS_FAILED,
                   error=f"the worker process died ({how}), {times}", attempt=job.attempt)


def _exit_reason(code: int | None) -> str:
    if code is not None and code < 0:
        try:
            return signal.Signals(-code).name
        except ValueError:
            return f"signal {-code}"
    return f"exit code {code}"


def _context() -> multiprocessing.context.BaseContext:
    """Fork-server processes where the platform has them (a fork of an interpreter that has
    already imported vtrack and the main script: fast to start, and safe, it runs no threads);
    spawn elsewhere. Preloading ``__main__`` keeps each child from running the main script
    again (multiprocessing's main-module fix-up)."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["__main__", __name__])
        with _safe_path():
            forkserver.ensure_running()
        return context
    return multiprocessing.get_context("spawn")


@contextmanager
def _safe_path() -> Iterator[None]:
    """Start child interpreters without the current folder first on ``sys.path``.

    The fork server is ``python -c ...``, which puts ``''`` (the current folder) first on
    ``sys.path`` and, on Python 3.11, never takes the parent's path: run from a folder that
    holds a ``vtrack/`` folder (the folder of a clone), every worker imported that folder
    instead of the installed package (issue 11 item 2). ``PYTHONSAFEPATH`` (Python >= 3.11)
    keeps the child from adding it; the rest of ``sys.path`` (``PYTHONPATH``, site-packages,
    editable installs) is unchanged.
    """
    saved = os.environ.get("PYTHONSAFEPATH")
    os.environ["PYTHONSAFEPATH"] = "1"
    try:
        yield
    finally:
        if saved is None:
            del os.environ["PYTHONSAFEPATH"]
        else:
            os.environ["PYTHONSAFEPATH"] = saved


class _Worker:
    """A long-lived local worker process, its end of the pipe, and the job it is running."""

    def __init__(self, context: multiprocessing.context.BaseContext) -> None:
        self.connection, theirs = context.Pipe()
        self.process = context.Process(target=_serve, args=(theirs,), daemon=True,
                                       name="vtrack batch worker")
        self.process.start()
        theirs.close()  # the worker holds the only other end: EOF here when it dies
        self.job: Job | None = None

    def start(self, job: Job) -> bool:
        """Hand ``job`` to the worker; False if it is gone."""
        self.job = job
        try:
            self.connection.send(job)
        except OSError:
            return False
        return True

    def result(self) -> Outcome | Progress | None:
        """The next message about the running job: its progress, its outcome, or None if the
        worker died first."""
        try:
            return self.connection.recv()
        except (EOFError, OSError):
            return None

    def stop(self, grace_s: float = STOP_GRACE_S,
             signum: signal.Signals = signal.SIGTERM) -> None:
        """:func:`stop_workers` of this worker alone."""
        stop_workers([self], grace_s, signum)

    def ended_by(self, deadline: float) -> bool:
        """Whether the worker's end of the pipe closes (it is gone) by ``deadline``
        (``time.monotonic``); what it sends meanwhile (an outcome or progress nobody waits for
        now) is dropped."""
        try:
            while (left := deadline - time.monotonic()) > 0 and self.connection.poll(left):
                self.connection.recv()
        except (EOFError, OSError):
            return True
        return False


def stop_workers(workers: Sequence[_Worker], grace_s: float = STOP_GRACE_S,
                 signum: signal.Signals = signal.SIGTERM) -> None:
    """Ask every worker to finish, together: the jobs still running share ``grace_s`` to end,
    then their workers get ``signum`` (the signal the batch was stopped by: SIGINT, SIGTERM),
    so each job ends ``interrupted`` with its outputs whole and its ``run.json`` written,
    naming that signal, and they share :data:`RECORD_GRACE_S` to do so; only then are the
    processes still there killed. (One after the other, each busy worker would add its whole
    wait: a stop's time would grow with the workers, past what ``docker stop`` allows.)

    A worker's exit is read from its end of the pipe closing, not from ``Process.join``: the
    worker is the forkserver's child, and a signal to the whole process group (Ctrl-C,
    ``timeout``, a scheduler's SIGTERM) may have ended the forkserver, whose lost status pipe
    makes ``join`` return at once with exit code 255 while the worker still writes its
    records (``summary.csv`` was then written without them)."""
    for worker in workers:
        with suppress(OSError):
            worker.connection.send(None)
    running = list(workers)
    for wait_s, then in ((grace_s, signum), (RECORD_GRACE_S, signal.SIGKILL)):
        deadline = time.monotonic() + wait_s
        running = [worker for worker in running if not worker.ended_by(deadline)]
        for worker in running:
            with suppress(ProcessLookupError):
                os.kill(worker.process.pid, then)
    for worker in workers:
        worker.process.join(1)
        worker.connection.close()


class LocalExecutor:
    """At most ``workers`` long-lived worker processes, each running one job at a time.

    Unlike a ``ProcessPoolExecutor`` (which breaks entirely, ``BrokenProcessPool``, when one of
    its workers dies), every worker has its own pipe and the executor knows which job each one
    runs: a worker that dies (killed, segfault) costs only that job, which is started again on
    a fresh worker :data:`RETRIES` times and then reported ``failed``; the other workers carry
    on. Workers stay alive between jobs, so a job starts warm (imports, codec and OpenCV set-up
    are done once per worker, not once per job).
    """

    def __init__(self, workers: int,
                 on_progress: Callable[[Progress], None] | None = None) -> None:
        self.workers = max(1, workers)
        #: Called with each running job's :class:`Progress` as its worker reports it.
        self.on_progress = on_progress

    def run(self, jobs: Sequence[Job]) -> Generator[Outcome, None, None]:
        context = _context()
        pending = deque(jobs)
        workers: list[_Worker] = []
        stop = _StopSignal(signal.SIGTERM)  # (a worker lost, or the consumer gone: not a signal)
        try:
            with stop.watch():
                while pending or workers:
                    # a worker for each pending job no idle worker will take, up to self.workers
                    idle = sum(worker.job is None for worker in workers)
                    while len(workers) < self.workers and idle < len(pending):
                        workers.append(_Worker(context))
                        idle += 1
                    lost = []  # workers found dead, with the job they had
                    for worker in workers:
                        if worker.job is None and pending and not worker.start(pending.popleft()):
                            lost.append(worker)
                    busy = {w.connection: w for w in workers if w.job is not None and w not in lost}
                    for connection in wait(list(busy)) if busy else ():
                        worker = busy[connection]
                        outcome = worker.result()
                        if isinstance(outcome, Progress):
                            if self.on_progress is not None:
                                self.on_progress(outcome)
                            continue
                        if outcome is None:
                            lost.append(worker)
                        else:
                            worker.job = None
                            yield outcome
                    for worker in lost:
                        workers.remove(worker)
                        worker.stop()
                        job = worker.job
                        if job.attempt <= RETRIES:
                            pending.appendleft(replace(job, attempt=job.attempt + 1))
                        else:
                            yield _died(job, _exit_reason(worker.process.exitcode))
                    if not pending and all(w.job is None for w in workers):
                        return
        finally:
            # a running job ends naming the signal the batch got
            stop_workers(workers, signum=stop.signum)


class DaskExecutor:
    """Jobs as tasks on an existing Dask distributed scheduler (``pip install vtrack[dask]``).

    Connects when created (so a wrong address fails before anything runs) and disconnects at
    the end of :meth:`run`: one run per executor. Only the small :class:`Job` objects travel;
    workers read inputs by path and write results to the output path, which they must share
    with this machine. Dask reschedules a task whose worker died; once the scheduler's
    ``allowed-failures`` is exceeded it gives up and the job is reported ``failed``. Each job's
    OpenCV threads are chosen on the worker that runs it, from that machine's cores
    (:func:`~vtrack.batch.worker.dask_threads`), never from this one's.
    """

    def __init__(self, address: str, timeout_s: float = 10) -> None:
        try:
            from distributed import Client
        except ImportError:
            raise VtrackError(
                "--scheduler needs Dask distributed: pip install 'vtrack[dask]'") from None
        problem = scheduler_address_problem(address)
        if problem:
            raise VtrackError(f"--scheduler {address}: {problem}")
        self.address = address
        self.scheduler_timeout_s = timeout_s
        self.worker_timeout_s: float | None = None
        try:
            _probe(address, timeout_s)
            with _quiet_client_teardown():
                self.client = Client(address, timeout=timeout_s, set_as_default=False)
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise VtrackError(
                f"--scheduler {address}: cannot reach the Dask scheduler ({reason})"
            ) from None

    def wait_for_workers(self, timeout_s: float | None,
                         say: Callable[[str], None] = lambda line: None) -> None:
        """Return once at least one worker is connected to the scheduler; if none is, ``say``
        so (one line) and wait up to ``timeout_s`` seconds (None: for ever). On expiry, or when
        the scheduler goes away meanwhile, the client is closed and a :class:`VtrackError`
        names the scheduler and what happened; as it does when a connected worker cannot run
        the batch's jobs (:meth:`_refuse_workers_without_vtrack`)."""
        self.worker_timeout_s = timeout_s
        if not self.client.scheduler_info().get("workers"):
            self._wait_for_a_worker(timeout_s, say)
        self._refuse_workers_without_vtrack()

    def _wait_for_a_worker(self, timeout_s: float | None, say: Callable[[str], None]) -> None:
        """:meth:`wait_for_workers`' wait, when no worker is connected yet."""
        limit = "for ever" if timeout_s is None else f"up to {_seconds(timeout_s)}"
        say(f"vtrack: waiting for a Dask worker to connect to {self.address} ({limit}, "
            f"--worker-timeout)")
        try:  # (only the wait: an error of ``say`` is no lost scheduler)
            with _client_log_off():  # (its "Failed to reconnect": the error line below says so)
                self.client.wait_for_workers(1, timeout=timeout_s)
        except TimeoutError:
            self.close()
            raise VtrackError(f"--scheduler {self.address}: no Dask worker connected within "
                              f"{_seconds(timeout_s or 0)} (--worker-timeout)") from None
        except OSError as exc:  # CommClosedError: the scheduler stopped, its machine went away
            self.close()
            raise VtrackError(f"--scheduler {self.address}: lost the connection to the "
                              f"scheduler before a worker connected "
                              f"({lost_reason(exc, self.scheduler_timeout_s)})") from None

    def _refuse_workers_without_vtrack(self) -> None:
        """Ask every connected worker which vtrack it imports, before any job is sent: a
        worker without vtrack would die unpickling the first job (its ``dask worker`` ends,
        and the batch could only say that no worker is connected), and one of another version
        may read a job otherwise. Each is given :data:`ASK_WORKER_S` at most (the worker
        timeout, if shorter): one stopped (``kill -STOP``) or gone cannot hold the batch. A
        :class:`VtrackError` (the client closed) names the first worker that has another
        vtrack, none it can import, or did not answer, and the version the batch needs. (A
        worker that connects later is not asked.)"""
        from vtrack import __version__

        limit_s = min(self.worker_timeout_s or ASK_WORKER_S, ASK_WORKER_S)
        # (every worker: some Dask releases list 5 unless told otherwise, as worker.py says)
        workers = sorted(self.client.scheduler_info(n_workers=-1).get("workers", {}))
        answers = self.client.sync(_ask_workers, self.client, workers, limit_s)
        for worker, answer in sorted(answers.items()):
            if answer == __version__:
                continue
            reason = str(answer).splitlines()[0] if str(answer) else type(answer).__name__
            need = (f"every worker needs vtrack {__version__}, the batch's (pip install "
                    f"'vtrack[dask]=={__version__}' where it runs)")
            if isinstance(answer, str):
                has = f"has vtrack {answer}"
            elif isinstance(answer, (ImportError, AttributeError)):
                has = f"has no vtrack it can import ({reason})"
            elif isinstance(answer, OSError):  # (TimeoutError, CommClosedError: it left)
                has = f"did not answer which vtrack it imports ({reason})"
                need = ("no job is sent before every connected worker has (a stopped worker: "
                        "resume or end it; one that left as it was asked: run the batch again)")
            else:
                has = f"cannot import vtrack ({type(answer).__name__}: {reason})"
            others = len(answers) - 1
            also = f" ({others} other worker{'s' if others > 1 else ''} connected)"
            self.close()
            raise VtrackError(f"--scheduler {self.address}: worker {worker} {has}; {need}"
                              + (also if others else ""))

    def close(self) -> None:
        """Disconnect; nothing is printed if the scheduler is already gone (the Client's
        attempt to reconnect to a lost scheduler, cancelled here, logs a traceback at ERROR
        otherwise: the jobs' lines already say the scheduler was lost)."""
        with _client_log_off(), _quiet_client_teardown(), suppress(Exception):
            self.client.close()

    def run(self, jobs: Sequence[Job]) -> Generator[Outcome, None, None]:
        """Submit every job and yield outcomes as they finish. When no worker has been
        connected for the worker timeout (:meth:`wait_for_workers`; every worker died), the
        jobs still pending are cancelled and reported ``failed``, naming the scheduler. A job
        is released once its outcome is taken: the scheduler forgets it, so a worker that dies
        holding its result does not make Dask run it again (rewriting the folder the batch has
        reported and read its summary row from). Stopped
        part way (Ctrl-C, SIGTERM: the consumer closes this generator), running jobs are stopped
        too (:meth:`_stop_running`), their records naming the signal the batch got."""
        from distributed import Event, as_completed

        batch = uuid.uuid4().hex[:8]
        stop = Event(f"vtrack-{batch}-stop", client=self.client)
        futures = {self.client.submit(execute_on_dask, job, stop.name,
                                      pure=False,
                                      key=f"vtrack-{batch}-{n}-{job.input}-{job.config}"): job
                   for n, job in enumerate(jobs)}
        finished = as_completed(futures, loop=self.client.loop)
        seen = checked = time.monotonic()
        ended_early = True  # (until the batch ends by itself)
        stop_with = _StopSignal(signal.SIGINT)  # (the consumer gone without a signal: as on Ctrl-C)
        try:
            with stop_with.watch():
                while not finished.is_empty():
                    if finished.has_ready():
                        for future in finished.next_batch(block=False):
                            outcome = self._outcome(future, futures[future])
                            future.release()  # (else Dask runs it again if its worker dies)
                            yield outcome
                        continue
                    time.sleep(0.05)
                    now = time.monotonic()
                    if now - checked < WORKER_POLL_S:
                        continue
                    checked = now
                    if self.client.scheduler_info().get("workers"):
                        seen = now
                    elif self.worker_timeout_s is not None and now - seen > self.worker_timeout_s:
                        for future, job in futures.items():
                            if not future.done():
                                yield Outcome(job.input, job.config, STATUS_FAILED, error=(
                                    f"Dask: no worker connected to {self.address} for "
                                    f"{_seconds(self.worker_timeout_s)} (--worker-timeout)"))
                        ended_early = False  # no worker is left to stop
                        return
                ended_early = False
        finally:
            if ended_early:
                self._stop_running(stop, [f for f in futures if not f.done()],
                                   stop_with.signum)
            with suppress(Exception):
                self.client.cancel(list(futures))
            self.close()

    def _stop_running(self, stop: Any, unfinished: list[Any], signum: signal.Signals,
                      grace_s: float = STOP_GRACE_S) -> None:
        """Stop a batch's tasks when it is stopped part way by ``signum`` (Ctrl-C, SIGTERM):
        ``signum`` is put in the Dask ``Variable`` beside ``stop``
        (:func:`~vtrack.batch.worker.stop_signal_name`), then ``stop`` is set, so a running
        job ends ``interrupted`` at its next progress check, with its records whole and its
        error naming that signal, and one that starts now returns without touching
        its folder; the tasks the scheduler has not handed to a worker are cancelled, those it
        has get ``grace_s`` to end. (Cancelling a Dask future does not stop a task already
        running: the worker went on and finished the job after the batch had reported it
        interrupted.) Nothing is asked of a scheduler that is gone (each call would wait for
        it), and the event is cleared and the variable deleted after, so the scheduler does not
        keep them."""
        from distributed import Variable

        if self.client.status != "running":
            return
        stop_signal = Variable(stop_signal_name(stop.name), client=self.client)
        with _quiet_client_teardown(), suppress(Exception):
            stop_signal.set(int(signum))
            stop.set()
            handed = {key for keys in self.client.processing().values() for key in keys}
            self.client.cancel([f for f in unfinished if f.key not in handed])
            started = [f for f in unfinished if f.key in handed]
            deadline = time.monotonic() + grace_s
            while any(not f.done() for f in started) and time.monotonic() < deadline:
                time.sleep(0.05)
        with _quiet_client_teardown(), suppress(Exception):
            stop.clear()
            stop_signal.delete()

    def _outcome(self, future: Any, job: Job) -> Outcome:
        """The job's outcome from its future; a task Dask could not finish (``KilledWorker``,
        the scheduler lost) is ``failed`` with one line saying why."""
        try:
            return future.result()
        except Exception as exc:  # KilledWorker, lost connection: report, carry on
            if getattr(exc, "reason", None) == "scheduler-connection-lost":
                error = (f"Dask: lost the connection to the scheduler {self.address} while "
                         "the job was pending or running; its outcome is unknown here: a "
                         "running job may still end on its worker and write its run.json (the "
                         "same vtrack batch again takes up a complete one, vtrack report "
                         "shows it)")
            else:
                first = str(exc).splitlines()[0] if str(exc).strip() else ""
                error = f"Dask: {type(exc).__name__}: {first}".rstrip(": ")
            return Outcome(job.input, job.config, STATUS_FAILED, error=error)


async def _ask_workers(client: Any, workers: list[str], limit_s: float) -> dict[str, object]:
    """Which vtrack each of ``workers`` (connected to ``client``'s scheduler) imports: its
    ``__version__``, the exception importing it raised (ImportError; AttributeError: no
    version), or a TimeoutError when it did not answer within ``limit_s`` seconds (an
    OSError when the scheduler could not reach it). Each worker is asked on its own, so one
    that does not answer hides no other's answer."""
    import asyncio

    async def ask(worker: str) -> dict[str, object]:
        # (a builtin, pickled by name: a worker unpickles it without vtrack)
        asked = client.run(eval, "__import__('vtrack').__version__", workers=[worker],
                           on_error="return", asynchronous=True)
        try:
            return await asyncio.wait_for(asked, limit_s)
        except TimeoutError:
            return {worker: TimeoutError(f"no answer within {_seconds(limit_s)}")}

    answers: dict[str, object] = {}
    for found in await asyncio.gather(*(ask(worker) for worker in workers)):
        answers.update(found)
    return answers


def _host_port(address: str) -> tuple[str, str, int | None]:
    """``(protocol, host, port)`` of a scheduler address (``tcp`` without ``PROTOCOL://``;
    port None when there is none); ValueError for a port that is not one."""
    protocol, sep, location = address.partition("://")
    if not sep:
        protocol, location = "tcp", address
    parts = urlsplit(f"//{location}")
    return protocol, parts.hostname or "", parts.port


def scheduler_address_problem(address: str) -> str | None:
    """What is wrong with ``address`` as ``--scheduler``'s (``tcp://HOST:PORT``), before
    anything connects to it; None if nothing is."""
    if not address.strip():
        return "no address: give the scheduler's, tcp://HOST:PORT"
    protocol = address.partition("://")[0] if "://" in address else "tcp"
    if protocol not in SCHEDULER_PROTOCOLS:
        known = " and ".join(f"{name}://" for name in SCHEDULER_PROTOCOLS)
        return (f"vtrack does not connect with {protocol}:// (it connects with {known}; "
                "a scheduler's address is tcp://HOST:PORT)")
    try:
        _, host, port = _host_port(address)
    except ValueError:  # not a number, or past 65535
        return "the port is not a number from 1 to 65535 (tcp://HOST:PORT)"
    location = address.partition("://")[2] if "://" in address else address
    netloc = urlsplit(f"//{location}").netloc  # (up to the first / ? or #)
    extra = location[len(netloc):]
    # a missing host or port first: dropping what follows leaves none (``tcp:///h:8786``)
    if not host:
        return "no host: give tcp://HOST:PORT"
    if port is None:
        return "no port: give tcp://HOST:PORT (a scheduler listens on 8786 unless told otherwise)"
    if extra:  # (Dask's address has no path: a scheduler there was called none)
        return f"nothing follows the port in tcp://HOST:PORT, not {quoted(extra)}: drop it"
    if "@" in netloc:  # (Dask's address has no user)
        return "no user@ in tcp://HOST:PORT: drop it"
    if port == 0:
        return "port 0 is no port a scheduler listens on (tcp://HOST:PORT)"
    return None


def _probe(address: str, timeout_s: float) -> None:
    """Ask the scheduler at ``address`` who it is, within ``timeout_s`` in all (connecting,
    the handshake, the answer): a peer that accepts and stays silent, or a port that is not a
    scheduler's (the dashboard's HTTP, a server that speaks another protocol first) raises
    TimeoutError or OSError here, before a Client (whose own timeout does not cover them)
    exists."""
    import asyncio

    from distributed.comm import connect

    async def ask() -> object:
        comm = await connect(address, timeout=timeout_s)  # (the handshake is read here)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    async def reachable() -> None:
        """Refused at once, not after Dask's retries for the whole timeout. (A scheduler logs
        this bare connection at INFO: "closed before handshake completed".)"""
        _, host, port = _host_port(address)
        try:
            _, writer = await asyncio.open_connection(host, port)
        except ConnectionRefusedError:
            raise OSError("connection refused") from None
        except socket.gaierror:
            raise OSError(f"no host named {quoted(host)} is known") from None
        writer.close()

    async def identity() -> None:
        await reachable()
        try:
            reply = await ask()
        except (OSError, TimeoutError, asyncio.CancelledError):
            raise
        except Exception:  # another protocol's bytes read as Dask's frames (sizes, msgpack)
            raise OSError("not a Dask scheduler") from None
        if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
            raise OSError("not a Dask scheduler")

    async def bounded() -> None:
        try:
            await asyncio.wait_for(identity(), timeout_s)
        except TimeoutError:
            raise TimeoutError(f"no answer within {_seconds(timeout_s)}") from None

    asyncio.run(bounded())


def lost_reason(exc: OSError, scheduler_timeout_s: float) -> str:
    """Why the connection to a scheduler was lost, from Dask's ``exc``: its last part
    (``[Errno 104] Connection reset by peer``); when the client's reconnection gave up ("Timed
    out trying to connect to tcp://... after 10 s"), the option that set that wait:
    ``no reconnection within 10 s, --scheduler-timeout``."""
    reason = str(exc).rsplit(": ", 1)[-1] or type(exc).__name__
    if reason.startswith("Timed out"):
        return f"no reconnection within {_seconds(scheduler_timeout_s)}, --scheduler-timeout"
    return reason


def _seconds(value: float) -> str:
    return f"{value:g} s"


@contextmanager
def _client_log_off() -> Iterator[None]:
    """Dask's ``distributed.client`` logger silenced: what it logs of a lost scheduler (its
    failed reconnection, at ERROR, with a traceback) is said in vtrack's own one line."""
    client_log = logging.getLogger("distributed.client")
    disabled, client_log.disabled = client_log.disabled, True
    try:
        yield
    finally:
        client_log.disabled = disabled


@contextmanager
def _quiet_client_teardown() -> Iterator[None]:
    """Collect a Dask ``Client`` that failed to connect (or was closed) here, without the
    ``Exception ignored in Client.__del__`` traceback its finaliser prints when it cannot
    reach the scheduler: the user already has the one-line error."""
    hook = sys.unraisablehook

    def ignore_client(unraisable: Any) -> None:
        if "Client" not in repr(getattr(unraisable, "object", "")):
            hook(unraisable)

    sys.unraisablehook = ignore_client
    try:
        yield
    finally:
        gc.collect()
        sys.unraisablehook = hook
