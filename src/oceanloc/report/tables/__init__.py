"""Terminal tables (rich), one module per domain; every column header states its unit."""
