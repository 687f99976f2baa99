"""Every scenario run in these tests reports only responses its module declares
(``RESPONSES``: the names a soil's ``simulation`` block may measure, checked at load)."""

import pytest

from soilcal.dem.scenarios import SCENARIOS


@pytest.fixture(autouse=True)
def _declared_responses(monkeypatch):
    for mod in set(SCENARIOS.values()):
        def checked(*args, _run=mod.run, _mod=mod, **kw):
            res = _run(*args, **kw)
            extra = set(res.responses) - set(_mod.RESPONSES)
            assert not extra, f"{_mod.NAME} reports undeclared responses {sorted(extra)}"
            return res
        monkeypatch.setattr(mod, "run", checked)
