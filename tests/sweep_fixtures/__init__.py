"""A small graph whose image depends on a param (a supersampled zone plate), for sweep tests."""
