"""A real S3-compatible server for the object-storage tests: moto's server mode, started as a
separate process on a free loopback port (the code under test talks HTTP to it, as to MinIO or
AWS; nothing in the client library is mocked)."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

CREDENTIALS = {
    "AWS_ACCESS_KEY_ID": "test-access-key",
    "AWS_SECRET_ACCESS_KEY": "test-secret-key",
    "AWS_DEFAULT_REGION": "us-east-1",
}


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@dataclass
class S3Server:
    endpoint: str
    bucket: str

    def client(self):
        import boto3

        return boto3.client(
            "s3",
            endpoint_url=self.endpoint,
            aws_access_key_id=CREDENTIALS["AWS_ACCESS_KEY_ID"],
            aws_secret_access_key=CREDENTIALS["AWS_SECRET_ACCESS_KEY"],
            region_name=CREDENTIALS["AWS_DEFAULT_REGION"],
        )

    def object_names(self) -> list[str]:
        pages = self.client().get_paginator("list_objects_v2").paginate(Bucket=self.bucket)
        return sorted(item["Key"] for page in pages for item in page.get("Contents", []))

    def env(self) -> dict[str, str]:
        """What a process needs to use the bucket as its storage."""
        return {**CREDENTIALS, "S3_BUCKET": self.bucket, "S3_ENDPOINT_URL": self.endpoint}

    def storages(self) -> dict:
        """The STORAGES setting webapp/settings.py builds from `env()`."""
        return {
            "default": {
                "BACKEND": "storages.backends.s3.S3Storage",
                "OPTIONS": {
                    "bucket_name": self.bucket,
                    "endpoint_url": self.endpoint,
                    "default_acl": None,
                    "file_overwrite": False,
                    "querystring_auth": True,
                },
            },
            "staticfiles": {"BACKEND": "django.contrib.staticfiles.storage.StaticFilesStorage"},
        }


def wait_for(endpoint: str, process: subprocess.Popen, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert process.poll() is None, "moto server exited"
        try:
            urllib.request.urlopen(endpoint + "/moto-api/", timeout=1).close()
            return
        except (urllib.error.URLError, ConnectionError, OSError):
            time.sleep(0.1)
    raise AssertionError("moto server did not answer")


@pytest.fixture
def s3_server(tmp_path: Path, monkeypatch) -> Iterator[S3Server]:
    """A fresh server with one empty bucket; this process's boto3 gets its credentials."""
    pytest.importorskip("moto.server", reason="needs moto[server] (the dev extra)")
    port = free_port()
    log = (tmp_path / "moto.log").open("ab")
    process = subprocess.Popen(
        [sys.executable, "-m", "moto.server", "-H", "127.0.0.1", "-p", str(port)],
        stdout=log,
        stderr=log,
        env={**os.environ, **CREDENTIALS},
    )
    try:
        endpoint = f"http://127.0.0.1:{port}"
        wait_for(endpoint, process)
        server = S3Server(endpoint, f"physio-{uuid.uuid4().hex[:8]}")
        server.client().create_bucket(Bucket=server.bucket)
        for name, value in CREDENTIALS.items():
            monkeypatch.setenv(name, value)
        yield server
    finally:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
        log.close()


def files_under(folder: Path) -> list[Path]:
    return [path for path in folder.rglob("*") if path.is_file()] if folder.exists() else []
