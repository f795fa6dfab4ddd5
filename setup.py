# Metadata lives in pyproject.toml; this stub only serves tools that still call setup.py.
import setuptools

setuptools.setup()
