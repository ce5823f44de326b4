"""A URL conf with one failing view, for the 500 page (the site's own handler500 included).

A module of its own so `webapp.urls` is imported only when a test loads this conf: importing it at
collection time, before pytest-django turns DEBUG off, would add the DEBUG-only media route.
"""

from __future__ import annotations

from django.urls import path

from webapp.urls import urlpatterns as site_patterns


def boom(request):
    raise RuntimeError("a failure the visitor must not see")


urlpatterns = [path("boom/", boom), *site_patterns]
handler500 = "webapp.help.views.server_error"
