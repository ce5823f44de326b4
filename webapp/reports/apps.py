from django.apps import AppConfig


class ReportsConfig(AppConfig):
    name = "webapp.reports"
    label = "reports"
    verbose_name = "Playback, charts and reports"

    def ready(self) -> None:
        # Registers the report task with the `workers` Celery app wherever Django starts.
        from webapp.reports import tasks  # noqa: F401
