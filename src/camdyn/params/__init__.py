"""Parameters: the system dataclasses, the law table, TOML configurations and presets."""
