"""`make run`'s terminal, read as the person who started it reads it.

`check_quiet_log` is run by tests/workers/test_make_run.py on the site it starts as `make run`
does (the launcher `workers.local`, `tests/local_server.py`): a refused request is one line with
its reason and no traceback, a successful status poll is not logged (a failed one is one line),
and nothing warns of a missing static folder. The filter's LOG_POLLS switch is tested here.
"""

from __future__ import annotations

import logging
import time
import uuid

import requests

from tests.local_server import LocalServer
from tests.personas import PASSWORD
from webapp.log_filters import QuietAccessLog


def signed_in(url: str, username: str) -> requests.Session:
    session = requests.Session()
    session.get(f"{url}/accounts/login/", timeout=10)
    form = {"username": username, "password": PASSWORD}
    form["csrfmiddlewaretoken"] = session.cookies["csrftoken"]
    answer = session.post(f"{url}/accounts/login/", data=form, timeout=30)
    assert answer.ok and "/accounts/login" not in answer.url
    return session


def check_quiet_log(server: LocalServer, therapist: str, exercise: str) -> None:
    """A therapist asks for the audit log (clinic admins only: 403), polls an exercise's model
    builds, polls a recording that does not exist (404), then opens the exercises' page."""
    session = signed_in(server.url, therapist)
    mark = server.log_path.stat().st_size
    assert session.get(f"{server.url}/audit/", timeout=10).status_code == 403
    polled = session.get(f"{server.url}/exercises/{exercise}/models.json", timeout=10)
    assert polled.status_code == 200
    missing = f"/recordings/{uuid.uuid4()}/status/"
    assert session.get(f"{server.url}{missing}", timeout=10).status_code == 404
    assert session.get(f"{server.url}/exercises/", timeout=10).status_code == 200
    log = wait_for(server, mark, "GET /exercises/ 200")
    refused = [line for line in log if "/audit/" in line]
    assert len(refused) == 1 and "Forbidden" in refused[0], log
    assert "clinic admin" in refused[0].lower(), log  # the reason, in the same line
    assert not [line for line in log if "models.json" in line], log  # a successful poll
    assert len([line for line in log if missing in line]) == 1, log  # a failed poll
    assert not [line for line in log if "Traceback" in line or line.startswith("  File ")], log
    assert "No directory at" not in server.log_path.read_text()


def wait_for(server: LocalServer, mark: int, text: str) -> list[str]:
    """The log written since ``mark`` once ``text`` is in it (the access line comes last)."""
    for _ in range(40):
        log = server.log_path.read_bytes()[mark:].decode(errors="replace").splitlines()
        if any(text in line for line in log):
            return log
        time.sleep(0.25)
    raise AssertionError("\n".join(log))


def access(path: str, status: int) -> logging.LogRecord:
    """An access line as daphne's runserver logs it: one mapping of details."""
    record = logging.LogRecord("django.channels.server", logging.INFO, __file__, 1,
                               "HTTP %(method)s %(path)s %(status)s", (), None)  # fmt: skip
    record.args = {"method": "GET", "path": path, "status": status}
    return record


def test_polls_are_logged_only_when_asked(monkeypatch):
    poll = f"/recordings/{uuid.uuid4()}/status/"
    quiet = QuietAccessLog()
    assert not quiet.filter(access(poll, 200)) and quiet.filter(access("/patients/", 200))
    assert not quiet.filter(access("/patients/", 403))  # said once, by the request logger
    monkeypatch.setenv("LOG_POLLS", "1")
    assert quiet.filter(access(poll, 200))
