"""Batch room: ``course grade`` in the trusted parent (driver, sessions, reports, marks, roster)."""
