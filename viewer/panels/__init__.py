"""The explorer's docks: parameters, bridges table, inspector, timeline, plot."""
