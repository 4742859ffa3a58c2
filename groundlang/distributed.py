"""Run independent pieces of work (evaluation folds, ablation cells) on a Ray cluster.

The same two functions the process pool uses drive Ray: ``init_worker(context)``
prepares a worker once and ``fold_fn(index) -> dict`` does one piece of work.
The context goes into the object store once; each Ray worker process fetches
and initialises it on its first task and keeps it (keyed by the object ref)
for every later task of the same run, so a worker pays for the context once,
not once per fold. Results come back in index order; a piece that raises comes
back as an error record ``{"index", "instance", "error", "seconds"}`` instead
of stopping the run.

Ray is an optional dependency (the ``ray`` extra); without it, asking for Ray
raises :class:`RayUnavailableError`, a ValueError the CLI reports in one line.
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import time
from collections.abc import Callable, Iterator, Sequence

__all__ = ["RayUnavailableError", "ray_session", "run_on_ray"]

log = logging.getLogger(__name__)

INSTALL_HINT = "install the ray extra: pip install 'groundlang[ray]' (in a clone: pip install -e '.[ray]')"

# In a Ray worker process: the context this worker was initialised with, and its object ref's hex id.
_WORKER_CONTEXT: dict = {"key": None, "context": None}


class RayUnavailableError(ValueError):
    """Ray was asked for but is not installed."""


def _import_ray():
    try:
        import ray
    except ImportError:
        raise RayUnavailableError(f"--ray needs the Ray package, which is not installed; {INSTALL_HINT}") from None
    return ray


def _register_serializers(ray) -> None:
    """Teach Ray to ship objects that hold parsed clingo programs (not picklable as they are).

    A Program is rebuilt on the worker from its sources, which re-parses the
    ASP text: cheap, and exact, since the sources are all a Program is made of.
    """
    from groundlang.logic.program import Program

    ray.util.register_serializer(
        Program,
        serializer=lambda p: (p.sources, p.allow_scripts, p.isolated),
        deserializer=lambda args: Program(*args),
    )


CONNECT_TIMEOUT = 10.0  # seconds to reach a "host:port" address before ray.init, which may wait for minutes


def _check_reachable(address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """Refuse a ``host:port`` (or ``ray://host:port``) address nothing answers at, within ``timeout`` s:
    given an unreachable address, ``ray.init`` retried for more than ten minutes, printing only its own
    warnings."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not host or not (port.isascii() and port.isdigit()):  # "²" is a digit to isdigit, not to int
        return  # "auto", or a form Ray itself judges
    if not 0 < int(port) < 65536:
        raise ValueError(f"Ray address {address}: port {port} is not a TCP port (1 to 65535)")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
            pass
    except OSError as exc:
        raise ValueError(f"Ray address {address}: no Ray cluster answers there ({exc.strerror or exc}); start "
                         "one with `ray start --head` (it prints its address), or give `auto` or `local`") from None


@contextlib.contextmanager
def ray_session(address: str, num_cpus: int | None = None, **init_options) -> Iterator[object]:
    """Connect to Ray for the duration of a block; yields the ``ray`` module.

    ``address``: ``"local"`` starts a local instance with ``num_cpus`` CPUs
    (default: all of this machine's); ``"auto"`` or ``"host:port"`` joins a
    running cluster; ``init_options`` go to ``ray.init`` (e.g. ``runtime_env``).
    When Ray is already initialised (an enclosing session), it is reused and
    left running; otherwise it is shut down on exit.
    """
    ray = _import_ray()
    started = False
    if not ray.is_initialized():
        options = dict(include_dashboard=False, log_to_driver=False, configure_logging=False) | init_options
        if address == "local":
            ray.init(num_cpus=num_cpus or os.cpu_count() or 1, **options)
        else:
            _check_reachable(address)
            ray.init(address=address, **options)
        started = True
        log.info("ray: connected (%s), %s CPUs", address, ray.cluster_resources().get("CPU", "?"))
    _register_serializers(ray)
    try:
        yield ray
    finally:
        if started:
            ray.shutdown()


def _describe(context, index: int) -> str:
    """A name for an error record: the instance's name when the context has instances."""
    try:
        return str(context["instances"][index].name)
    except (KeyError, IndexError, TypeError, AttributeError):
        return f"piece {index}"


def _run_piece(init_worker: Callable, fold_fn: Callable, boxed_ref: list, index: int) -> dict:
    """One task on a Ray worker: initialise once per context, then run ``fold_fn(index)``."""
    import ray

    started = time.perf_counter()
    (ref,) = boxed_ref  # boxed so that Ray hands over the ref, not a fresh copy of the context per task
    key = ref.hex()
    try:
        if _WORKER_CONTEXT["key"] != key:
            _WORKER_CONTEXT.update(key=None, context=ray.get(ref))
            init_worker(_WORKER_CONTEXT["context"])
            _WORKER_CONTEXT["key"] = key  # only once init_worker succeeded
        return fold_fn(index)
    except Exception as exc:  # a failing piece is reported, not fatal: the others still count
        return {"index": index, "instance": _describe(_WORKER_CONTEXT.get("context"), index),
                "error": f"{type(exc).__name__}: {exc}", "seconds": time.perf_counter() - started}


def run_on_ray(
    init_worker: Callable[[object], None],
    fold_fn: Callable[[int], dict],
    context: object,
    indices: Sequence[int],
    address: str,
    num_cpus: int | None = None,
) -> list[dict]:
    """``[fold_fn(i) for i in indices]`` on Ray workers, in index order.

    ``init_worker`` and ``fold_fn`` must be importable module-level functions
    (workers import them by name). ``address`` as in :func:`ray_session`.
    Raises RayUnavailableError without Ray; a task whose worker died comes
    back as an error record like a task that raised.
    """
    indices = list(indices)
    with ray_session(address, num_cpus) as ray:
        started = time.perf_counter()
        ref = ray.put(context)
        remote = ray.remote(num_cpus=1, max_retries=0)(_run_piece)
        futures = [remote.remote(init_worker, fold_fn, [ref], i) for i in indices]
        records = []
        for i, future in zip(indices, futures):
            try:
                records.append(ray.get(future))
            except ray.exceptions.RayError as exc:  # worker crash, out of memory, cancelled
                records.append({"index": i, "instance": _describe(context, i),
                                "error": f"{type(exc).__name__}: {' '.join(str(exc).split())[:500]}",
                                "seconds": time.perf_counter() - started})
        log.info("ray: %d pieces in %.1f s", len(indices), time.perf_counter() - started)
        return records
