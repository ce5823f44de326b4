from django.urls import path, re_path

from webapp.help import views

app_name = "help"

urlpatterns = [
    path("", views.guide, name="guide"),
    # Only the guide's own screenshots: no other file under docs/ is reachable.
    re_path(r"^img/(?P<name>guide-[a-z0-9-]+\.png)$", views.guide_image, name="image"),
]
