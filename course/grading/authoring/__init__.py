"""Authoring room: what the instructor writes and hands out (checks, release, seals, export)."""
