"""Demo and scale data: the demo clinic (`manage.py load_demo`) and a large synthetic clinic for
scale measurements (`manage.py fill_large_clinic`). They go through the same services as any
other caller of the web app."""
