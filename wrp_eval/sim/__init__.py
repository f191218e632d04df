"""The sim stage (see README.md in this folder)."""
