"""HTTP routers: plans, simulations, runs, health and the map page."""
