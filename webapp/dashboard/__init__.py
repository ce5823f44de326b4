"""The therapist's home page (patients needing attention, runs under way) and the health check."""
