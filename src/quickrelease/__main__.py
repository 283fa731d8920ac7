"""``python -m quickrelease``: the same command line as the ``quickrelease`` script."""

from .cli import main

if __name__ == "__main__":
    main()
