"""The planning stage (see README.md in this folder)."""
