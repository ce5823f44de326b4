from django.urls import path

from webapp.live.consumers import LiveConsumer

websocket_urlpatterns = [
    path("ws/live/<uuid:session_id>/", LiveConsumer.as_asgi()),
]
