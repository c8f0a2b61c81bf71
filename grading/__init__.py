"""Instructor-only grading tools (never shipped in the student release)."""
