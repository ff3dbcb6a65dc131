"""Built-in dataset manifests (TOML), read with :func:`lorisnb.io.manifest.read_manifest`."""
