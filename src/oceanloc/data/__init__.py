"""Small real data sets shipped with oceanloc (each folder holds its licence and a README)."""
