"""Paper tables and figures from a campaign's index and case folders."""
