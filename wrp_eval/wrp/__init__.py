"""The wrp stage (see README.md in this folder)."""
