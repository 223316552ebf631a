"""Account administration, password changes and resets, invitations by link, and the robots table."""
