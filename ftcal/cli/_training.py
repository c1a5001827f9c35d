"""Training with a progress bar: epochs of the skorch networks, a timer for closed-form fits."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator
from typing import Any

from ._common import Console

__all__ = ["fit_with_progress", "ticking"]

_PROGRESS = "cli_progress"


def _callback_class():
    """The skorch callback class (built on first use, so importing the CLI does not import torch)."""
    from skorch.callbacks import Callback

    class _EpochProgress(Callback):
        def __init__(self, bar: Any) -> None:
            self.bar = bar

        def on_epoch_end(self, net, **kwargs: Any) -> None:
            last = net.history[-1]
            post = {k: f"{last[k]:.4g}" for k in ("train_loss", "valid_loss") if k in last}
            if "lr" in last:  # recorded every epoch by the schedule (its TrainingPhase callback)
                post["lr"] = f"{last['lr']:.1e}"
            self.bar.set_postfix(post, refresh=False)
            self.bar.update(1)
            if len(net.history) == 1:  # show the first losses at once, not after tqdm's mininterval
                self.bar.refresh()

    return _EpochProgress


def fit_with_progress(estimator: Any, X: Any, y: Any, console: Console, label: str = "fit", **fit_params: Any) -> Any:
    """``estimator.fit(X, y)`` with a progress bar on stderr (none when ``console.quiet``).

    Networks (estimators with a ``callbacks`` parameter) get a per-epoch bar
    with the training / validation loss; other estimators get an elapsed-time
    bar. Returns the fitted estimator.
    """
    params = estimator.get_params(deep=False) if hasattr(estimator, "get_params") else {}
    if console.quiet:
        return estimator.fit(X, y, **fit_params)
    if "callbacks" in params:
        schedule = getattr(estimator, "_schedule_epochs", None)  # the epochs of a three-phase schedule, at most
        bar = console.progress(total=int(schedule()[1]) if callable(schedule) else None, desc=f"{label} epochs",
                               unit="epoch")
        installed = _progress_callback_installed(estimator, params["callbacks"], _callback_class()(bar))
    else:
        bar = console.progress(total=None, desc=f"{label}", bar_format="{desc}: {elapsed} elapsed")
        installed = ticking(bar.refresh)
    try:
        with installed:
            return estimator.fit(X, y, **fit_params)
    finally:
        bar.close()


@contextlib.contextmanager
def _progress_callback_installed(estimator: Any, callbacks: Any, callback: Any) -> Iterator[None]:
    """Add ``callback`` to the estimator's ``callbacks`` parameter for this fit only.

    Afterwards the parameter is restored and the bar is dropped from the
    fitted skorch net, so the fitted model stays a plain one (it may be
    pickled or cloned later).
    """
    estimator.set_params(callbacks=list(callbacks or []) + [(_PROGRESS, callback)])
    try:
        yield
    finally:
        estimator.set_params(callbacks=callbacks)
        net = getattr(estimator, "net_", None)
        if net is not None:
            net.callbacks_ = [(n, cb) for n, cb in net.callbacks_ if n != _PROGRESS]
            net.callbacks = [c for c in (net.callbacks or []) if not (isinstance(c, tuple) and c[0] == _PROGRESS)]


@contextlib.contextmanager
def ticking(tick: Callable[[], None], name: str = "ftcal-progress") -> Iterator[None]:
    """Within the block, ``tick()`` runs every half second on a daemon thread (a timer bar's redraw, a heartbeat)."""
    done = threading.Event()

    def run() -> None:
        while not done.wait(0.5):
            tick()

    thread = threading.Thread(target=run, daemon=True, name=name)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()
