"""tillpath's I/O layer: the web application, storage and the command line."""
