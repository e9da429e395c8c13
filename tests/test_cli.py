"""The command line's own options."""
import pytest

from dacph_drake.app.cli import main


def test_version_prints_the_installed_version(capsys):
    from importlib.metadata import version
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"dacph {version('dacph-drake')}"
