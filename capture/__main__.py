"""``python -m capture``: the capture client's own entry point (`capture.stream`), so that the
analysis command line never needs the network packages it uses."""

from capture.stream import main

if __name__ == "__main__":
    raise SystemExit(main())
