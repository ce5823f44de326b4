"""The Django project: settings, URLs and the clinic apps."""
