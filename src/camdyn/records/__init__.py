"""Measured and synthetic records: the channel schema and synthetic measurements."""
