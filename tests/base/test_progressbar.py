"""lmic.progressbar: the one progress bar (drawn on a terminal; a log, a final summary or nothing elsewhere)."""

from __future__ import annotations

import pytest

from lmic.progressbar import ProgressBar


def _steps(bar: ProgressBar) -> None:
    bar.update(total=2, completed=1, description="solving with a", line="[1/2] a: solved")
    bar.update(advance=1, info="b: certified", line="[2/2] b: solved")


def test_off_a_terminal_it_is_silent_or_a_log_or_a_final_summary(capsys, monkeypatch):
    monkeypatch.delenv("FORCE_COLOR", raising=False)
    monkeypatch.setenv("TERM", "dumb")
    monkeypatch.setenv("COLUMNS", "200")  # the summary on one line
    with ProgressBar("work") as bar:
        _steps(bar)
    assert capsys.readouterr().err == ""
    with ProgressBar("work", log=True) as bar:
        _steps(bar)
    assert capsys.readouterr().err == "[1/2] a: solved\n[2/2] b: solved\n"
    with ProgressBar("work", summary=True, rate="jobs", eta=True) as bar:
        _steps(bar)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "solving with a" in err and "2/2" in err and "jobs/s" in err
    assert "b: certified" in err and "ETA" in err
    with ProgressBar("work", enabled=False, log=True, summary=True) as bar:
        _steps(bar)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("spinner", [False, True])
def test_on_a_terminal_the_bar_is_drawn_and_a_transient_one_erased(capsys, monkeypatch, spinner):
    monkeypatch.setenv("FORCE_COLOR", "1")  # rich: standard error counts as a terminal
    with ProgressBar("work", log=True, spinner=spinner) as bar:
        assert bar.drawn
        _steps(bar)
    err = capsys.readouterr().err
    assert "2/2" in err and "b: certified" in err and "[1/2] a: solved" not in err  # drawn, not logged
    assert not err.endswith("\x1b[2K")  # the final state stays
    with ProgressBar("work", transient=True) as bar:
        _steps(bar)
    assert capsys.readouterr().err.endswith("\r\x1b[1A\x1b[2K")  # the bar's line erased
