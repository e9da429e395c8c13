"""Where a scenario's sections meet their implementations (registry) and its files."""
