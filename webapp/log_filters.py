"""Filters that keep the server's log to one useful line per event (webapp/settings.py LOGGING).

* A refused request (4xx) is one line from Django's request logger, with the reason a 403 gave,
  never a traceback: a refusal is the site working, not a fault. 5xx keep their traceback.
* The development server's access line of a refused request says nothing more than that line,
  so it is left out; so is the access line of a successful status poll (pages ask every second
  or two while an analysis runs), unless ``LOG_POLLS=1`` asks for them.
"""

from __future__ import annotations

import logging
import os
import re

# What the pages poll: a recording's status, an exercise's model builds, the home page's list.
POLLS = re.compile(r"^/(recordings/[^/]+/status/|exercises/[^/]+/models\.json)|format=json")


def log_polls() -> bool:
    return os.environ.get("LOG_POLLS", "").strip().lower() in {"1", "true", "yes", "on"}


class RefusalInOneLine(logging.Filter):
    """django.request: a 4xx record without its traceback, the refusal's reason appended."""

    def filter(self, record: logging.LogRecord) -> bool:
        status = getattr(record, "status_code", 500)
        if status >= 500 or not record.exc_info:
            return True
        reason = str(record.exc_info[1] or "").strip()
        record.msg = f"{record.getMessage()}{f' ({reason})' if reason else ''}"
        record.args = None
        record.exc_info, record.exc_text = None, None
        return True


class QuietAccessLog(logging.Filter):
    """django.channels.server (runserver's access lines): drop refused requests (the request
    logger has said so) and successful polls (unless LOG_POLLS=1)."""

    def filter(self, record: logging.LogRecord) -> bool:
        details = record.args if isinstance(record.args, dict) else None
        if details is None or "status" not in details:
            return True
        status = int(details.get("status") or 0)
        if 400 <= status < 500:
            return False
        return not (status < 400 and POLLS.search(str(details.get("path", ""))) and not log_polls())
