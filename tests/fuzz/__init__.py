"""The boundary fuzz test: every public callable with malformed arguments (issue 16)."""
