"""The surrogate stage (see README.md in this folder)."""
