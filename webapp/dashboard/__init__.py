"""The therapist's home page, health check and the demo clinic loader."""
