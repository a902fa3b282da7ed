"""The web dashboard (issue 18)."""
