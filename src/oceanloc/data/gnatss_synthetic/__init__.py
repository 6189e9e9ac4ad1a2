"""A small synthetic GNSS-A array survey in GNATSS's formats (see README.md)."""
