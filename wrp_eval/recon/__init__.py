"""The recon stage (see README.md in this folder)."""
