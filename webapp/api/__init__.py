"""REST API (Django REST framework) for other systems: patient history, exercises, uploads."""
