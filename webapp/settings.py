"""One settings module, driven by environment variables with safe local defaults.

SQLite and in-process (eager) Celery by default; PostgreSQL with ``DATABASE_URL`` and a real
broker with ``REDIS_URL``. Refuses to start with ``DEBUG`` off and the development secret key.
"""

from __future__ import annotations

import os
from pathlib import Path

import dj_database_url
from celery.schedules import crontab
from django.core.exceptions import ImproperlyConfigured

BASE_DIR = Path(__file__).resolve().parent.parent
DEV_SECRET_KEY = "dev-insecure-secret-key-change-me"


def env_bool(name: str, default: bool) -> bool:
    value = os.environ.get(name)
    if value is None:
        return default
    return value.strip().lower() in {"1", "true", "yes", "on"}


def env_list(name: str, default: str) -> list[str]:
    return [item.strip() for item in os.environ.get(name, default).split(",") if item.strip()]


DEBUG = env_bool("DEBUG", True)
SECRET_KEY = os.environ.get("SECRET_KEY", DEV_SECRET_KEY)
if not DEBUG and SECRET_KEY == DEV_SECRET_KEY:
    raise ImproperlyConfigured(
        "Set SECRET_KEY: DEBUG is off and the development secret key is in use."
    )

# The demo clinic has published passwords: the loader runs only where this is switched on
# explicitly (`make demo` and `make run` do), whatever DEBUG says.
DEMO_ALLOWED = env_bool("DEMO_ALLOWED", False)

ALLOWED_HOSTS = env_list("ALLOWED_HOSTS", "localhost,127.0.0.1,[::1],testserver")
CSRF_TRUSTED_ORIGINS = env_list("CSRF_TRUSTED_ORIGINS", "")

INSTALLED_APPS = [
    "daphne",  # first: makes `manage.py runserver` an ASGI server (live sessions' WebSockets)
    "django.contrib.admin",
    "django.contrib.auth",
    "django.contrib.contenttypes",
    "django.contrib.sessions",
    "django.contrib.messages",
    "django.contrib.staticfiles",
    "django_otp",
    "django_otp.plugins.otp_totp",
    "webapp.accounts",
    "webapp.patients",
    "webapp.exercises",
    "webapp.recordings",
    "webapp.dashboard",
    "webapp.demo",
    "webapp.audit",
    "webapp.api",
    "webapp.reports",
    "webapp.live",
    "channels",
    "rest_framework",
    "axes",
    "drf_spectacular",
    "drf_spectacular_sidecar",
]

# Uploads: the largest recording accepted, in bytes (a 10-minute 120 fps take is about 40 MB).
MAX_UPLOAD_BYTES = int(os.environ.get("MAX_UPLOAD_BYTES", str(64 * 1024 * 1024)))
DATA_UPLOAD_MAX_MEMORY_SIZE = 2 * 1024 * 1024
# What a recording may be before it is analysed (analysis.bvh.plausibility; checked on upload, by
# the worker and by the pipeline): its length, its frames, and the memory its analysis may need.
RECORDING_MAX_SECONDS = float(os.environ.get("RECORDING_MAX_SECONDS", "1800"))
RECORDING_MAX_FRAMES = int(os.environ.get("RECORDING_MAX_FRAMES", "500000"))
RECORDING_MAX_ANALYSIS_BYTES = int(os.environ.get("RECORDING_MAX_ANALYSIS_BYTES", str(2 << 30)))

MIDDLEWARE = [
    "django.middleware.security.SecurityMiddleware",
    "whitenoise.middleware.WhiteNoiseMiddleware",
    "django.contrib.sessions.middleware.SessionMiddleware",
    "django.middleware.common.CommonMiddleware",
    "django.middleware.csrf.CsrfViewMiddleware",
    "django.contrib.auth.middleware.AuthenticationMiddleware",
    "django_otp.middleware.OTPMiddleware",
    "webapp.accounts.two_factor.TwoFactorMiddleware",
    "django.contrib.messages.middleware.MessageMiddleware",
    "django.middleware.clickjacking.XFrameOptionsMiddleware",
    # Remembers the request for the audit log's write events (model signals have no request).
    "webapp.audit.context.AuditContextMiddleware",
    # Last, as django-axes asks: turns a locked-out login into a 429 page.
    "axes.middleware.AxesMiddleware",
]

ROOT_URLCONF = "webapp.urls"
WSGI_APPLICATION = "webapp.wsgi.application"
ASGI_APPLICATION = "webapp.asgi.application"

TEMPLATES = [
    {
        "BACKEND": "django.template.backends.django.DjangoTemplates",
        "DIRS": [BASE_DIR / "templates"],
        "APP_DIRS": True,
        "OPTIONS": {
            "context_processors": [
                "django.template.context_processors.request",
                "django.contrib.auth.context_processors.auth",
                "django.contrib.messages.context_processors.messages",
            ],
        },
    },
]

DATA_DIR = Path(os.environ.get("DATA_DIR", BASE_DIR / "var"))
# The default SQLite file (and local media) live here: a fresh clone has no such folder yet.
DATA_DIR.mkdir(parents=True, exist_ok=True)
DATABASES = {
    "default": dj_database_url.config(
        default=f"sqlite:///{DATA_DIR / 'db.sqlite3'}", conn_max_age=60
    )
}
DEFAULT_AUTO_FIELD = "django.db.models.BigAutoField"
AUTH_USER_MODEL = "accounts.User"

AUTH_PASSWORD_VALIDATORS = [
    {"NAME": "django.contrib.auth.password_validation.UserAttributeSimilarityValidator"},
    {"NAME": "django.contrib.auth.password_validation.MinimumLengthValidator"},
    {"NAME": "django.contrib.auth.password_validation.CommonPasswordValidator"},
    {"NAME": "django.contrib.auth.password_validation.NumericPasswordValidator"},
]

LANGUAGE_CODE = "en-gb"
TIME_ZONE = os.environ.get("TIME_ZONE", "UTC")
USE_I18N = True
USE_TZ = True

STATIC_URL = "/static/"
STATIC_ROOT = Path(os.environ.get("STATIC_ROOT", BASE_DIR / "staticfiles"))
# three.js comes from the npm registry (package.json) and is served as a static file: no CDN.
# Only the two folders the pages import from: WhiteNoise indexes every file of these folders
# each time the middleware starts (every test client), and the whole package holds 1,000 files.
_THREE = BASE_DIR / "node_modules" / "three"
STATICFILES_DIRS = [
    BASE_DIR / "webapp" / "static",
    ("vendor/three/build", _THREE / "build"),
    ("vendor/three/examples/jsm/controls", _THREE / "examples" / "jsm" / "controls"),
    ("vendor/plotly", Path(__import__("plotly").__file__).parent / "package_data"),
    # the camera page's pose engine (npm @mediapipe/pose: its script, WebAssembly and models)
    ("vendor/mediapipe/pose", BASE_DIR / "node_modules" / "@mediapipe" / "pose"),
]
# Static files straight from their folders (no collectstatic): with DEBUG on, and under `make
# run`'s launcher, which serves with DEBUG off (workers/local.py sets it).
WHITENOISE_USE_FINDERS = env_bool("WHITENOISE_USE_FINDERS", DEBUG)
MEDIA_URL = "/media/"
MEDIA_ROOT = Path(os.environ.get("MEDIA_ROOT", DATA_DIR / "media"))

# Files (uploads, result arrays, tutors, exercise models, reports) go through Django's default
# storage only: the local folder MEDIA_ROOT by default, an S3-compatible bucket when S3_BUCKET is
# set (credentials from AWS_ACCESS_KEY_ID / AWS_SECRET_ACCESS_KEY, or the machine's role;
# S3_ENDPOINT_URL for MinIO and the like). Workers on other machines then share nothing but
# PostgreSQL, Redis and the bucket (docs/RELIABILITY.md).
S3_BUCKET = os.environ.get("S3_BUCKET", "")
STORAGES = {
    "default": {"BACKEND": "django.core.files.storage.FileSystemStorage"},
    "staticfiles": {"BACKEND": "django.contrib.staticfiles.storage.StaticFilesStorage"},
}
if S3_BUCKET:
    STORAGES["default"] = {
        "BACKEND": "storages.backends.s3.S3Storage",
        "OPTIONS": {
            "bucket_name": S3_BUCKET,
            "endpoint_url": os.environ.get("S3_ENDPOINT_URL") or None,
            "region_name": os.environ.get("S3_REGION") or None,
            "location": os.environ.get("S3_PREFIX", ""),
            # Health data: private objects, never overwritten (names get a suffix instead).
            "default_acl": None,
            "file_overwrite": False,
            "querystring_auth": True,
            "addressing_style": os.environ.get("S3_ADDRESSING_STYLE") or None,
        },
    }

OTP_TOTP_ISSUER = "Physio dashboard"
LOGIN_URL = "accounts:login"
LOGIN_REDIRECT_URL = "dashboard:home"
LOGOUT_REDIRECT_URL = "accounts:login"
EMAIL_BACKEND = os.environ.get("EMAIL_BACKEND", "django.core.mail.backends.console.EmailBackend")
# Outgoing mail (password resets, reminders of missed sessions): SMTP when EMAIL_BACKEND says so.
EMAIL_HOST = os.environ.get("EMAIL_HOST", "localhost")
EMAIL_PORT = int(os.environ.get("EMAIL_PORT", "25"))
EMAIL_HOST_USER = os.environ.get("EMAIL_HOST_USER", "")
EMAIL_HOST_PASSWORD = os.environ.get("EMAIL_HOST_PASSWORD", "")
EMAIL_USE_TLS = env_bool("EMAIL_USE_TLS", False)
DEFAULT_FROM_EMAIL = os.environ.get("DEFAULT_FROM_EMAIL", "physio-dashboard@localhost")
# The site's address as patients reach it ("https://physio.example.org"), for links in e-mails.
SITE_URL = os.environ.get("SITE_URL", "")

# Security (issue 8). Production (DEBUG off) is HTTPS-only unless the environment says otherwise;
# `manage.py check --deploy` is clean with these defaults (tests/webapp/test_deploy_check.py).
SESSION_COOKIE_SECURE = env_bool("SESSION_COOKIE_SECURE", not DEBUG)
CSRF_COOKIE_SECURE = env_bool("CSRF_COOKIE_SECURE", not DEBUG)
SESSION_COOKIE_HTTPONLY = True
SESSION_COOKIE_SAMESITE = "Lax"
# A shared clinic computer: sessions end after 8 hours and when the browser closes.
SESSION_COOKIE_AGE = int(os.environ.get("SESSION_COOKIE_AGE", str(8 * 3600)))
SESSION_EXPIRE_AT_BROWSER_CLOSE = True
SECURE_SSL_REDIRECT = env_bool("SECURE_SSL_REDIRECT", not DEBUG)
# Health checks of the container come over plain HTTP from inside the host.
SECURE_REDIRECT_EXEMPT = [r"^healthz$"]
SECURE_HSTS_SECONDS = int(os.environ.get("SECURE_HSTS_SECONDS", "0" if DEBUG else "31536000"))
SECURE_HSTS_INCLUDE_SUBDOMAINS = env_bool("SECURE_HSTS_INCLUDE_SUBDOMAINS", not DEBUG)
SECURE_HSTS_PRELOAD = env_bool("SECURE_HSTS_PRELOAD", not DEBUG)
SECURE_CONTENT_TYPE_NOSNIFF = True
SECURE_REFERRER_POLICY = "same-origin"
X_FRAME_OPTIONS = "DENY"
# Behind a TLS-terminating proxy that sets X-Forwarded-Proto (set SECURE_PROXY_SSL_HEADER=1).
if env_bool("SECURE_PROXY_SSL_HEADER", False):
    SECURE_PROXY_SSL_HEADER = ("HTTP_X_FORWARDED_PROTO", "https")

# Login rate limiting (django-axes): after AXES_FAILURE_LIMIT failed passwords for one username,
# or from one client address, that username (address) is locked for AXES_COOLOFF_HOURS, on the
# login page and on the API token endpoint alike. Behind a reverse proxy, set
# TRUSTED_PROXY_COUNT so the address is the client's (X-Forwarded-For), not the proxy's.
AUTHENTICATION_BACKENDS = [
    "webapp.accounts.lockout.ClinicAxesBackend",
    "django.contrib.auth.backends.ModelBackend",
]
AXES_FAILURE_LIMIT = int(os.environ.get("AXES_FAILURE_LIMIT", "5"))
AXES_COOLOFF_TIME = float(os.environ.get("AXES_COOLOFF_HOURS", "0.25"))
AXES_LOCKOUT_PARAMETERS = env_list("AXES_LOCKOUT_BY", "username,ip_address")
if os.environ.get("TRUSTED_PROXY_COUNT"):
    AXES_IPWARE_PROXY_COUNT = int(os.environ["TRUSTED_PROXY_COUNT"])
    AXES_IPWARE_META_PRECEDENCE_ORDER = ["HTTP_X_FORWARDED_FOR", "REMOTE_ADDR"]
AXES_RESET_ON_SUCCESS = True
AXES_LOCKOUT_CALLABLE = "webapp.accounts.lockout.lockout_response"
AXES_USERNAME_FORM_FIELD = "username"

# API tokens (webapp.accounts.tokens): days a token obtained with a password stays valid.
API_TOKEN_DAYS = int(os.environ.get("API_TOKEN_DAYS", "30"))

# Celery: eager (in-process) when no broker is configured, so `make run` needs no services.
REDIS_URL = os.environ.get("REDIS_URL", "")
CELERY_BROKER_URL = REDIS_URL or "memory://"
# Live sessions: WebSocket groups on Redis when configured, in memory (one process) otherwise.
_REDIS_LAYER = {
    "BACKEND": "channels_redis.core.RedisChannelLayer",
    # redis-py 8 reads with a 5 s timeout by default, the same as channels_redis's blocking pop:
    # a connection that heard nothing for 5 s would then fail. Reads wait longer than the pop.
    "CONFIG": {"hosts": [{"address": REDIS_URL, "socket_timeout": 30}]},
}
CHANNEL_LAYERS = {
    "default": _REDIS_LAYER if REDIS_URL else {"BACKEND": "channels.layers.InMemoryChannelLayer"}
}
LIVE_MAX_FPS = float(os.environ.get("LIVE_MAX_FPS", "1000"))  # frames/s per session, then dropped
LIVE_BURST = float(os.environ.get("LIVE_BURST", "250"))
CELERY_RESULT_BACKEND = REDIS_URL or None
CELERY_TASK_ALWAYS_EAGER = not REDIS_URL
CELERY_TASK_EAGER_PROPAGATES = True
# Queues (workers/celery.py routes each task): analyses (and the short housekeeping tasks) on
# CELERY_QUEUE, model builds and PDF reports on queues of their own, so a slow build or report
# never waits in front of an analysis. `make worker` consumes all three; see docs/RELIABILITY.md.
CELERY_TASK_DEFAULT_QUEUE = os.environ.get("CELERY_QUEUE", "analyses")
CELERY_MODELS_QUEUE = os.environ.get("CELERY_MODELS_QUEUE", "models")
CELERY_REPORTS_QUEUE = os.environ.get("CELERY_REPORTS_QUEUE", "reports")
CELERY_TASK_SERIALIZER = "json"
CELERY_RESULT_SERIALIZER = "json"
CELERY_ACCEPT_CONTENT = ["json"]
CELERY_TASK_ACKS_LATE = True
CELERY_TASK_REJECT_ON_WORKER_LOST = True
CELERY_WORKER_PREFETCH_MULTIPLIER = 1
CELERY_RESULT_EXPIRES = 3600
ANALYSIS_SOFT_TIME_LIMIT = int(os.environ.get("ANALYSIS_SOFT_TIME_LIMIT", "300"))
ANALYSIS_TIME_LIMIT = int(os.environ.get("ANALYSIS_TIME_LIMIT", "360"))
# Each worker pool process may hold this much memory (MB; 0: no ceiling); an analysis needing
# more fails with a plain reason instead of bringing the machine down (workers/limits.py).
ANALYSIS_MEMORY_LIMIT_MB = int(os.environ.get("ANALYSIS_MEMORY_LIMIT_MB", "3072"))
# A run whose worker died under it this many times fails with a reason; never claimed again.
ANALYSIS_MAX_ATTEMPTS = int(os.environ.get("ANALYSIS_MAX_ATTEMPTS", "2"))
# A RUNNING run whose worker has not reported for this long may be claimed again (worker died).
ANALYSIS_LEASE_SECONDS = int(os.environ.get("ANALYSIS_LEASE_SECONDS", "60"))
# Paper 002 retrieval: principal components of the 2-bit codes, and how many recordings to compare.
RETRIEVAL_COMPONENTS = int(os.environ.get("RETRIEVAL_COMPONENTS", "4"))
RETRIEVAL_MAX_CANDIDATES = int(os.environ.get("RETRIEVAL_MAX_CANDIDATES", "200"))
# Fault injection only (tests/workers/test_worker_crash.py): seconds slept after each stage.
ANALYSIS_STAGE_DELAY_SECONDS = float(os.environ.get("ANALYSIS_STAGE_DELAY_SECONDS", "0"))
# A QUEUED run not started within this time had its message lost (broker restarted empty): the
# beat task enqueues it again, at most ANALYSIS_MAX_ENQUEUES times in all, then fails it.
ANALYSIS_REQUEUE_AFTER_SECONDS = int(os.environ.get("ANALYSIS_REQUEUE_AFTER_SECONDS", "600"))
ANALYSIS_MAX_ENQUEUES = int(os.environ.get("ANALYSIS_MAX_ENQUEUES", "4"))
# Deleted patients are hidden at once and purged (rows and files) after this many days.
PATIENT_RETENTION_DAYS = int(os.environ.get("PATIENT_RETENTION_DAYS", "30"))
CELERY_TASK_SOFT_TIME_LIMIT = ANALYSIS_SOFT_TIME_LIMIT
CELERY_TASK_TIME_LIMIT = ANALYSIS_TIME_LIMIT
# A message not acknowledged within this time is delivered again: keep it above the longest task.
CELERY_BROKER_TRANSPORT_OPTIONS = {
    "visibility_timeout": int(os.environ.get("BROKER_VISIBILITY_TIMEOUT", ANALYSIS_TIME_LIMIT * 2))
}
CELERY_BROKER_CONNECTION_RETRY_ON_STARTUP = True
# `make run` (workers/local.py) sets LOCAL_BROKER_DIR: a real Celery worker process runs beside
# the server and messages are files in that folder (kombu's filesystem transport), so an upload
# returns at once with nothing to install. REDIS_URL, when set, wins.
LOCAL_BROKER_DIR = os.environ.get("LOCAL_BROKER_DIR", "")
if LOCAL_BROKER_DIR and not REDIS_URL:
    CELERY_BROKER_URL = "filesystem://"
    CELERY_TASK_ALWAYS_EAGER = False
    CELERY_BROKER_TRANSPORT_OPTIONS = {
        "data_folder_in": str(Path(LOCAL_BROKER_DIR) / "queue"),
        "data_folder_out": str(Path(LOCAL_BROKER_DIR) / "queue"),
        "control_folder": str(Path(LOCAL_BROKER_DIR) / "control"),
        "polling_interval": 0.2,  # seconds between looks at the folder when it is empty
    }
    if DATABASES["default"]["ENGINE"].endswith("sqlite3"):
        # Two processes write the SQLite file (server and worker): readers never wait for the
        # worker's progress writes (WAL), and a writer waits for the other instead of failing.
        DATABASES["default"].setdefault("OPTIONS", {}).update(
            timeout=30, init_command="PRAGMA journal_mode=WAL;", transaction_mode="IMMEDIATE"
        )
REMINDER_HOUR = int(os.environ.get("REMINDER_HOUR", "17"))
CELERY_TIMEZONE = TIME_ZONE  # crontab entries below read the clinic's hours
CELERY_BEAT_SCHEDULE = {
    "reap-stuck-runs": {"task": "workers.tasks.reap_stuck_runs", "schedule": 60.0},
    "requeue-lost-runs": {"task": "workers.tasks.requeue_lost_runs", "schedule": 60.0},
    "purge-deleted-patients": {"task": "workers.tasks.purge_deleted_patients", "schedule": 86400.0},
    "rebuild-models-with-corrections": {
        "task": "workers.tasks.rebuild_models_with_corrections",
        "schedule": 3600.0,
    },
    "refit-pass-thresholds": {"task": "workers.tasks.refit_pass_thresholds", "schedule": 3600.0},
    # The home page's stored attention list: runs refresh their patient on write; this catches
    # what changes with time alone (failures ageing out, sessions missed).
    "refresh-attention": {"task": "workers.tasks.refresh_attention", "schedule": 600.0},
    # E-mail reminders of missed sessions (webapp.patients.reminders), daily at REMINDER_HOUR
    # in TIME_ZONE, leaving the evening to exercise; at most one per patient a day whatever runs.
    "send-reminders": {
        "task": "workers.tasks.send_reminders",
        "schedule": crontab(hour=REMINDER_HOUR, minute=0),
    },
}

REST_FRAMEWORK = {
    "DEFAULT_AUTHENTICATION_CLASSES": [
        # Hashed, clinic-scoped, revocable tokens: `Authorization: Token <key>`.
        "webapp.accounts.authentication.ClinicTokenAuthentication",
        "rest_framework.authentication.SessionAuthentication",
    ],
    "DEFAULT_PERMISSION_CLASSES": ["rest_framework.permissions.IsAuthenticated"],
    "DEFAULT_PAGINATION_CLASS": "rest_framework.pagination.LimitOffsetPagination",
    "PAGE_SIZE": 50,
    # drf-spectacular, plus the 400/401/403/404 answers (tests/webapp/test_schemathesis.py).
    "DEFAULT_SCHEMA_CLASS": "webapp.api.schema.ApiSchema",
}
SPECTACULAR_SETTINGS = {
    "TITLE": "Physio dashboard API",
    "DESCRIPTION": (
        "Patient history, exercises and recording uploads for practice-management systems."
    ),
    "VERSION": "1.0.0",
    "SERVE_INCLUDE_SCHEMA": False,
    # Swagger UI from the sidecar package: the docs page works offline.
    "SWAGGER_UI_DIST": "SIDECAR",
    # No badge that sends the schema's address to Swagger's online validator (a third party).
    "SWAGGER_UI_SETTINGS": {"deepLinking": True, "validatorUrl": None},
    "SWAGGER_UI_FAVICON_HREF": "SIDECAR",
    "REDOC_DIST": "SIDECAR",
    # Several "status" fields: each set of states gets its own schema name.
    "ENUM_NAME_OVERRIDES": {
        "AnalysisStatusEnum": "webapp.recordings.models.RunStatus",
        "ModelStatusEnum": "webapp.exercises.models.ModelStatus",
        "LiveSessionStatusEnum": "webapp.live.models.LiveStatus",
        "RecordingStatusEnum": "webapp.api.serializers.RUN_STATES",
    },
    # The analysis result's components, generated from its dataclasses (webapp/api/result_schema).
    "POSTPROCESSING_HOOKS": [
        "drf_spectacular.hooks.postprocess_schema_enums",
        "webapp.api.result_schema.add_result_components",
        "webapp.api.schema.finish_schema",  # error bodies, null and score (webapp/api/schema)
    ],
}

LOGGING = {
    "version": 1,
    "disable_existing_loggers": False,
    # One line per refused request, no traceback; status polls only with LOG_POLLS=1
    # (webapp/log_filters.py).
    "filters": {
        "refusal_in_one_line": {"()": "webapp.log_filters.RefusalInOneLine"},
        "quiet_access_log": {"()": "webapp.log_filters.QuietAccessLog"},
    },
    "handlers": {"console": {"class": "logging.StreamHandler"}},
    "root": {"handlers": ["console"], "level": os.environ.get("LOG_LEVEL", "INFO")},
    "loggers": {
        # django-axes reports every successful login at INFO; failures and lockouts are warnings.
        "axes": {"level": os.environ.get("AXES_LOG_LEVEL", "WARNING")},
        "django.request": {"filters": ["refusal_in_one_line"]},
        "django.channels.server": {"filters": ["quiet_access_log"]},
    },
}
