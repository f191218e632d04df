"""The wind stage (see README.md in this folder)."""
