"""The papers' example systems, one module per example (plain data + functions)."""
