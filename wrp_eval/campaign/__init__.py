"""The campaign stage (see README.md in this folder)."""
