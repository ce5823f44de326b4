"""Numerical core: BVH, kinematics, alignment, landmarks, periodic analysis, assessment.

This package imports only the standard library, numpy, scipy, scikit-learn and small numeric
libraries; it never imports Django, Celery or the web app.
"""

__version__ = "0.1.0"
