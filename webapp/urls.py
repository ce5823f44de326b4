from django.conf import settings
from django.contrib import admin
from django.urls import include, path

from webapp.dashboard.views import healthz
from webapp.help.views import favicon

urlpatterns = [
    path("healthz", healthz, name="healthz"),
    path("favicon.ico", favicon, name="favicon"),
    path("help/", include("webapp.help.urls")),
    path("accounts/", include("webapp.accounts.urls")),
    path("admin/", admin.site.urls),
    path("audit/", include("webapp.audit.urls")),
    path("api/", include("webapp.api.urls")),
    path("patients/", include("webapp.patients.urls")),
    path("exercises/", include("webapp.exercises.urls")),
    path("recordings/", include("webapp.recordings.urls")),
    path("live/", include("webapp.live.urls")),
    path("my/live/camera/", include("webapp.live.camera_urls")),
    path("", include("webapp.reports.urls")),
    path("", include("webapp.dashboard.urls")),
]

# The 500 page in the site's layout, rendered without context processors (webapp/help/views.py).
handler500 = "webapp.help.views.server_error"

if settings.DEBUG:
    from django.conf.urls.static import static

    urlpatterns += static(settings.MEDIA_URL, document_root=settings.MEDIA_ROOT)
