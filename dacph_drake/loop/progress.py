"""Progress bars: tqdm (a widget in Jupyter, a bar with rate and ETA on a terminal); in a
log file or CI, redrawn at most once a minute."""
import sys

from tqdm.auto import tqdm

LOG_REDRAW_PERIOD = 60.0        # [s] between redraws when stderr is not interactive


def progress_bar(total: float, desc: str, unit: str, enabled: bool = True,
                 initial: float = 0) -> tqdm:
    """Makes a progress bar on stderr.

    Args:
        total: Where it ends.
        desc: Its label.
        unit: What it counts.
        enabled: False gives a no-op bar with the same methods.
        initial: Where it starts.

    Returns:
        The tqdm bar."""
    interactive = tqdm.__module__ == "tqdm.notebook" or sys.stderr.isatty()
    return tqdm(total=total, initial=initial, desc=desc, unit=unit, disable=not enabled,
                file=sys.stderr, dynamic_ncols=True,
                mininterval=0.5 if interactive else LOG_REDRAW_PERIOD,
                maxinterval=max(10.0, 0.5 if interactive else LOG_REDRAW_PERIOD))
