"""Accounts and authentication: who may log in and as what."""
