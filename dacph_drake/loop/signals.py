"""A run's signals by name (python-control's TimeResponseData, Drake's namedview): the
controllers' log columns by their log_layout names (``alpha_error``, ``e_tau`` ...), other
logs by their own (``u``, ``state`` ...), ``LOG.NAME`` where a name is in two logs."""
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from dacph_drake.log_layout import LearnerLog, RhsLog
from dacph_drake.tasks.registry import TASKS

# The controllers' logs whose columns are named, beside each task's (Task.LogLayout;
# n: the number of joints).
CONTROLLER_LAYOUTS = {"rhs_log": RhsLog, "learner_log": lambda n: LearnerLog()}
# Names of the task logs' columns, beside their layout's.
ALIASES = {"attitude_error": "e", "attitude_error_norm": "e_norm",
           "position_error": "e_position", "position_error_norm": "e_position_norm",
           "position_desired": "desired_position", "attitude_desired": "desired",
           "V": "lyapunov_V"}


def signal_index(logs: Dict[str, np.ndarray]) -> Dict[str, Tuple[str, object]]:
    """Every signal name of a run's logs -> (log, column index or slice).

    Args:
        logs: The run's logs (time first, one row per sample).

    Returns:
        The index; a log without a layout is its own signal (column slice(None))."""
    n = logs["u"].shape[1] if "u" in logs else 0
    layouts = {**CONTROLLER_LAYOUTS, **{task.log_name: task.LogLayout
                                        for task in TASKS.values()}}
    index, seen = {}, {}
    for log, values in logs.items():
        if log == "time":
            continue
        index[log] = (log, slice(None))
        if log not in layouts:
            continue
        layout = layouts[log](n)
        for name, column in vars(layout).items():
            if name == "size" or not isinstance(column, (int, slice)):
                continue
            index[f"{log}.{name}"] = (log, column)
            seen.setdefault(name, []).append(log)
    for name, logs_with_it in seen.items():
        if len(logs_with_it) == 1 and name not in index:
            index[name] = index[f"{logs_with_it[0]}.{name}"]
    for log in dict.fromkeys(task.log_name for task in TASKS.values()):
        for alias, name in ALIASES.items():
            if f"{log}.{name}" in index and alias not in index:
                index[alias] = index[f"{log}.{name}"]
    return index


class Signals:
    """A run's signals by name, each over time (T, or T x k); a batch's: trials first.

    Args:
        time: The logged times [s] (T).
        logs: Each trial's logs, one dict per trial."""

    def __init__(self, time: np.ndarray, logs: Sequence[Dict[str, np.ndarray]]):
        self.time = np.asarray(time)
        self._logs = list(logs)
        self._index = signal_index(self._logs[0])

    @classmethod
    def Of(cls, results: Sequence) -> "Signals":
        """A batch's trials' signals as traces (nan after a trial's early stop).

        Args:
            results: The trials' loop.run_store.RunResult (one batch's time grid)."""
        longest = max(results, key=lambda r: len(r.logs["time"]))
        return cls(longest.logs["time"], [r.logs for r in results])

    @property
    def names(self) -> List[str]:
        """Every name this run answers to."""
        return sorted(self._index)

    def __contains__(self, name: str) -> bool:
        return name in self._index

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        if name not in self._index:
            import difflib
            close = difflib.get_close_matches(name, self._index, n=3)
            raise KeyError(f"{name!r} is not a signal of this run"
                           + (f"; did you mean {', '.join(close)}?" if close else ""))
        log, column = self._index[name]
        traces = [logs[log][:, column] for logs in self._logs]
        if len(traces) == 1:
            return traces[0]
        out = np.full((len(traces), len(self.time)) + traces[0].shape[1:], np.nan)
        for k, trace in enumerate(traces):
            out[k, :len(trace)] = trace
        return out

    def to_pandas(self, names: Sequence[str] = ()):
        """A pandas DataFrame by time [s] (a batch: by trial, time), entries as NAME[i].

        Args:
            names: The signals (none: every log's named columns and raw logs)."""
        import pandas as pd
        names = list(names) or [name for name in self.names if "." not in name]
        frames = []
        for trial in range(len(self._logs)):
            columns = {}
            for name in names:
                values = np.asarray(self[name])
                values = values[trial] if len(self._logs) > 1 else values
                if values.ndim == 1:
                    columns[name] = values
                else:
                    columns.update({f"{name}[{i}]": values[:, i]
                                    for i in range(values.shape[1])})
            frame = pd.DataFrame(columns, index=pd.Index(self.time, name="time"))
            frames.append(frame)
        if len(frames) == 1:
            return frames[0]
        return pd.concat(frames, keys=range(len(frames)), names=["trial", "time"])

    def plot(self, *names: str, ax: Optional[object] = None, logy: bool = False) -> object:
        """Plots signals over time (a batch: one line per trial and entry).

        Args:
            *names: The signals.
            ax: A matplotlib Axes (None: a new figure's).
            logy: Absolute values on a log scale.

        Returns:
            The Axes."""
        import matplotlib.pyplot as plt
        if ax is None:
            ax = plt.figure().add_subplot()
        for name in names:
            values = np.asarray(self[name])
            traces = values if len(self._logs) > 1 else values[None]
            for k, trace in enumerate(traces):
                trace = trace.reshape(len(self.time), -1)
                for i in range(trace.shape[1]):
                    label = name + (f"[{i}]" if trace.shape[1] > 1 else "") + (
                        f", trial {k}" if len(traces) > 1 else "")
                    y = np.abs(trace[:, i]) if logy else trace[:, i]
                    (ax.semilogy if logy else ax.plot)(self.time, y, label=label)
        ax.set_xlabel("t [s]")
        ax.legend()
        return ax

