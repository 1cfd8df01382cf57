"""The ``pkmkit`` command line (thin layer over the library)."""
