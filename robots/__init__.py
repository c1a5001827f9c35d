"""The robot models ftcal ships (data only): installed as the package ``ftcal.robots`` (see pyproject.toml)."""
