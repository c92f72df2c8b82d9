"""Planning domains: graphs and seeded generative world models."""
