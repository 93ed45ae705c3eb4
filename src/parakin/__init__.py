"""parakin."""
