"""The package version; pyproject.toml's [project] version is the same (tests/test_api.py checks)."""

__version__ = "0.1.0"
