"""Comparisons of raycast with the references, ray by ray or file by file, and the reports
they write (validation, error bounds, error against time, signed distance, corpora)."""
