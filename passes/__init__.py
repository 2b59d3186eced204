"""Built-in pass implementations (installed as rgraph.passes)."""
