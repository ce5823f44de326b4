"""The guides, rendered from the Markdown files the repository keeps: docs/GUIDE.md for clinics,
docs/PATIENT_GUIDE.md for patients (in their words, no therapist's work).

The same file reads well on GitHub and in the site: its screenshots are linked as ``img/...``,
which resolves to ``docs/img/`` there and to ``/help/img/`` here.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import markdown
from django.conf import settings
from django.http import FileResponse, Http404, HttpRequest, HttpResponse, HttpResponseServerError
from django.shortcuts import redirect, render
from django.template import loader
from django.templatetags.static import static
from django.utils.safestring import SafeString, mark_safe

DOCS = Path(settings.BASE_DIR) / "docs"
GUIDE = DOCS / "GUIDE.md"
PATIENT_GUIDE = DOCS / "PATIENT_GUIDE.md"
PLAIN_500 = (
    "<!doctype html><title>Server error</title><h1>Something went wrong on our side</h1>"
    '<p>The error has been logged. <a href="/">Back to the home page</a></p>'
)


@lru_cache(maxsize=4)
def _rendered(path: Path, mtime_ns: int) -> SafeString:
    """The guide as HTML, rendered again only when the file changes (mtime is the cache key)."""
    del mtime_ns
    html = markdown.markdown(path.read_text(encoding="utf-8"), extensions=["tables", "toc"])
    # Our own file from the repository, not user input: safe to insert as HTML.
    return mark_safe(html)


def guide_html(path: Path = GUIDE) -> SafeString:
    return _rendered(path, path.stat().st_mtime_ns)


def guide(request: HttpRequest) -> HttpResponse:
    """The patients' guide to a patient (what to do, how to record, what the words mean), the
    clinics' guide to everyone else."""
    if getattr(request.user, "is_patient", False):
        context = {"guide": guide_html(PATIENT_GUIDE), "title": "Help"}
    else:
        context = {"guide": guide_html(GUIDE), "title": "Guide for clinics"}
    return render(request, "help/guide.html", context)


def guide_image(request: HttpRequest, name: str) -> FileResponse:
    path = DOCS / "img" / name
    if not path.is_file():
        raise Http404("No such picture in the guide.")
    return FileResponse(path.open("rb"), content_type="image/png")


def favicon(request: HttpRequest) -> HttpResponse:
    """Browsers ask for /favicon.ico whatever the page links: send them to the SVG icon."""
    return redirect(static("favicon.svg"))


def server_error(request: HttpRequest) -> HttpResponse:
    """The 500 page in the site's layout; plain HTML if even that fails, never a second error."""
    try:
        # No request context: context processors may be what failed (a broken database, say).
        return HttpResponseServerError(loader.get_template("500.html").render())
    except Exception:
        return HttpResponseServerError(PLAIN_500)
