"""A workflow job's bad input (soilcal.logs.redirect): one line in the log and on the real
standard error, exit status 2, no traceback; any other failure keeps its traceback."""

from __future__ import annotations

import logging
import subprocess
import sys
import textwrap

import pytest

from soilcal.errors import InputError
from soilcal.logs import redirect


def test_input_error_is_one_line_and_status_2(tmp_path, capsys):
    log = tmp_path / "logs/job.log"
    with pytest.raises(SystemExit) as exc:
        with redirect(log):
            print("measuring")
            raise InputError("photos/a.jpg", "file", "a complete, readable image", "0 bytes")
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err == "soilcal: error: photos/a.jpg: file: expected a complete, readable image, got '0 bytes'\n"
    text = log.read_text()
    assert "measuring" in text and "Traceback" not in text
    assert [ln for ln in text.splitlines() if "ERROR" in ln] == [
        ln for ln in text.splitlines() if ln.endswith("photos/a.jpg: file: expected a complete, readable image, got '0 bytes'")]


def test_other_failure_keeps_its_traceback_in_the_log(tmp_path):
    log = tmp_path / "job.log"
    handlers = list(logging.getLogger().handlers)
    with pytest.raises(ZeroDivisionError):
        with redirect(log):
            1 / 0
    assert "Traceback" in log.read_text() and "ZeroDivisionError" in log.read_text()
    assert logging.getLogger().handlers == handlers  # the job's log handler is removed again


def test_script_process_exits_2_without_traceback(tmp_path):
    script = tmp_path / "job.py"
    script.write_text(textwrap.dedent(f"""
        from soilcal.errors import InputError
        from soilcal.logs import redirect
        with redirect({str(tmp_path / 'job.log')!r}):
            raise InputError("tables/t.csv", "row 3, column A", "a number", "abc")
    """))
    p = subprocess.run([sys.executable, str(script)], capture_output=True, text=True)
    assert p.returncode == 2
    assert p.stderr == "soilcal: error: tables/t.csv: row 3, column A: expected a number, got 'abc'\n"
    assert p.stdout == ""
