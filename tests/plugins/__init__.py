"""Plug-ins of other packages, through real entry points."""
