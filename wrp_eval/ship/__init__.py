"""The ship stage (see README.md in this folder)."""
