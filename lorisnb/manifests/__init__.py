"""Built-in dataset manifests (TOML), read with :func:`lorisnb.io.datasets.manifest.read_manifest`."""
