"""Monte Carlo dispersion batches: spec and targets, batch execution, results."""
