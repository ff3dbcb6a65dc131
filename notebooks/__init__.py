"""lorisnb's notebooks, shipped as package data (``lorisnb.notebooks``): ``lorisnb report`` runs them."""
