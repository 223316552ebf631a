"""Every controlled session recorded to MCAP, replayed in the browser, exported; see README.md for the rules."""
