"""Bookings of robot time: a week calendar per robot, allowances, no-shows and an iCalendar export."""
