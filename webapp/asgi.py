"""ASGI entry point: HTTP through Django, WebSockets (live sessions) through Channels."""

import os

from django.core.asgi import get_asgi_application

os.environ.setdefault("DJANGO_SETTINGS_MODULE", "webapp.settings")
django_asgi = get_asgi_application()  # loads the apps before the consumers import models

from channels.auth import AuthMiddlewareStack  # noqa: E402
from channels.routing import ProtocolTypeRouter, URLRouter  # noqa: E402

from webapp.live.auth import BrowserOriginCheck  # noqa: E402
from webapp.live.routing import websocket_urlpatterns  # noqa: E402

application = ProtocolTypeRouter(
    {
        "http": django_asgi,
        "websocket": BrowserOriginCheck(AuthMiddlewareStack(URLRouter(websocket_urlpatterns))),
    }
)
