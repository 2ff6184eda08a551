"""Payload identification (paper section IV, eqs. 21-29): the four methods and their result.

Import from the modules of this package (or from `identify` for the public API)."""
