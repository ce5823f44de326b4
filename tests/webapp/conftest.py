import pytest
from django.test import Client as DjangoClient

from tests.personas import World, make_world
from tests.webapp.openapi_check import check_response


@pytest.fixture(autouse=True)
def _isolated_media(settings, tmp_path):
    settings.MEDIA_ROOT = tmp_path / "media"


@pytest.fixture(autouse=True)
def _eager_tasks():
    """Web tests run tasks in-process; the worker integration tests use a real worker."""
    from workers import app

    previous = app.conf.task_always_eager
    app.conf.task_always_eager = True
    yield
    app.conf.task_always_eager = previous


@pytest.fixture
def world(db) -> World:
    return make_world()


@pytest.fixture(autouse=True)
def _fast_password_hashing(settings):
    """Tests create many users: a cheap hasher keeps them fast (production uses the default)."""
    settings.PASSWORD_HASHERS = ["django.contrib.auth.hashers.MD5PasswordHasher"]


@pytest.fixture(autouse=True)
def _answers_fit_the_served_schema(monkeypatch):
    """Every `/api/v1/` answer any test's client receives is checked against the served OpenAPI
    schema (tests/webapp/openapi_check.py): a key, status or type it does not document fails
    the test that received it. DRF's APIClient sends its requests through Django's client."""
    sent = DjangoClient.request

    def request(self, **environ):
        response = sent(self, **environ)
        check_response(environ["REQUEST_METHOD"], environ["PATH_INFO"], response)
        return response

    monkeypatch.setattr(DjangoClient, "request", request)
