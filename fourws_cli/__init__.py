"""The `fourws` command line."""
