# The exact environment of a vibroimpact release, as an image (README, "Containers and conda"):
# Python 3.11, requirements.lock installed by pip with every file's hash checked, this package,
# and its numba kernels compiled into the image. From a clone at the release's tag:
#   docker build -t vibroimpact:<version> .          (or podman build; buildah bud)
#   apptainer build vibroimpact.sif docker-daemon://vibroimpact:<version>
# then `container: vibroimpact.sif` in your config and `snakemake --sdm apptainer`.
# BASE: any Debian-based image with Python 3.11 and its venv module (the official one by default).
ARG BASE=python:3.11-slim-bookworm
FROM ${BASE}

# git: the package's version comes from the clone's tags (setuptools-scm)
RUN apt-get update \
    && apt-get install -y --no-install-recommends git \
    && rm -rf /var/lib/apt/lists/*

ENV VIRTUAL_ENV=/opt/vibroimpact \
    PATH=/opt/vibroimpact/bin:$PATH
RUN python3 -m venv /opt/vibroimpact

# the lock alone first: this layer is rebuilt only when the lock changes
COPY requirements.lock /tmp/requirements.lock
RUN pip install --no-cache-dir --disable-pip-version-check --require-hashes --no-deps \
        -r /tmp/requirements.lock \
    && rm /tmp/requirements.lock

# the package, its version from the clone's git tags (setuptools-scm, from the lock)
COPY . /tmp/vibroimpact
RUN pip install --no-cache-dir --disable-pip-version-check --no-deps --no-build-isolation \
        /tmp/vibroimpact \
    && rm -rf /tmp/vibroimpact \
    && vibroimpact warm --jobs 2 \
    && vibroimpact --version

WORKDIR /work
CMD ["vibroimpact", "--help"]
