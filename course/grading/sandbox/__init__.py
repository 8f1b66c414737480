"""Sandbox room: the sandboxed grading children and the parent's handle on them."""
