# tillpath: the map page and the REST API, served by `tillpath serve` (uvicorn), with background
# jobs on Dask. Build and run with PostgreSQL: `docker compose up --build` (see docs/deploy.md).
# The same image runs the Dask scheduler and workers (`dask scheduler`, `dask worker …`).

# --- Front-end libraries (Leaflet, Leaflet-Geoman, Swagger UI) from npm, exactly as locked -----
# Node 24 is an LTS line (supported to April 2028). --ignore-scripts: no install-time scripts
# (swagger-ui-dist's @scarf/scarf would report the install).
FROM node:24-bookworm-slim AS frontend
WORKDIR /src
COPY package.json package-lock.json ./
RUN SCARF_ANALYTICS=false npm ci --no-audit --no-fund --omit=dev --ignore-scripts

# --- The wheel: the packages plus templates/, static/, the npm libraries and migrations --------
FROM python:3.11-slim-bookworm AS wheel
ENV PIP_NO_CACHE_DIR=1 PIP_DISABLE_PIP_VERSION_CHECK=1
WORKDIR /src
COPY pyproject.toml setup.py README.md alembic.ini package.json ./
COPY app ./app
COPY planner ./planner
COPY navigation ./navigation
COPY migrations ./migrations
COPY templates ./templates
COPY static ./static
COPY --from=frontend /src/node_modules ./node_modules
RUN pip wheel --no-deps -w /dist .

# --- The app -----------------------------------------------------------------------------------
FROM python:3.11-slim-bookworm

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1

# Dependencies first, exactly as locked, so that code changes rebuild only the last layer.
COPY requirements.lock /tmp/requirements.lock
RUN pip install -r /tmp/requirements.lock && rm /tmp/requirements.lock
COPY --from=wheel /dist /tmp/dist
RUN pip install --no-deps /tmp/dist/*.whl && rm -rf /tmp/dist

# Run unprivileged; the default SQLite database (no TILLPATH_DATABASE_URL) goes to /app/data.
RUN useradd --create-home --uid 10001 tillpath \
    && mkdir -p /app/data /app/numba-cache \
    && chown tillpath:tillpath /app/data /app/numba-cache
WORKDIR /app
USER tillpath
# The planner's numba kernels, compiled once here (seconds) rather than by every new
# container's first plan; site-packages is not writable for this user, so numba needs a
# directory it can write (and find again). Numba keys its cache on the CPU it compiled for:
# a generic target, so that the image's cache serves whatever machine runs it (no fastmath,
# so the same arithmetic; the code is a little slower than one built for the host).
ENV NUMBA_CACHE_DIR=/app/numba-cache NUMBA_CPU_NAME=generic
RUN python -c "from planner.warm_up import warm_up; warm_up()"

EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s --retries=3 \
    CMD ["python", "-c", "import sys, urllib.request; sys.exit(urllib.request.urlopen('http://127.0.0.1:8000/api/health', timeout=4).status != 200)"]

# Applies the migrations, starts (or joins) the job engine, then serves.
CMD ["tillpath", "serve", "--host", "0.0.0.0", "--port", "8000"]
