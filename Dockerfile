# tillpath: the map page and the REST API, served by `tillpath serve` (uvicorn).
# Build and run with PostgreSQL: `docker compose up --build` (see docs/deploy.md).

# --- Front-end libraries (Leaflet, Leaflet-Geoman) from the npm registry, exactly as locked ---
FROM node:20-bookworm-slim AS frontend
WORKDIR /app
COPY package.json package-lock.json ./
RUN npm ci --no-audit --no-fund --omit=dev

# --- The app -----------------------------------------------------------------------------------
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    # Import `app` from /app, not from site-packages: it finds templates/, static/,
    # node_modules/, alembic.ini and migrations/ beside itself.
    PYTHONPATH=/app

WORKDIR /app

# Dependencies first (pinned in pyproject.toml), so that code changes rebuild only the last layers.
COPY pyproject.toml README.md ./
COPY app ./app
COPY planner ./planner
COPY navigation ./navigation
RUN pip install .

COPY --from=frontend /app/node_modules ./node_modules
COPY alembic.ini ./
COPY migrations ./migrations
COPY templates ./templates
COPY static ./static

# Run unprivileged; the default SQLite database (no TILLPATH_DATABASE_URL) goes to /app/data.
RUN useradd --create-home --uid 10001 tillpath \
    && mkdir -p /app/data \
    && chown tillpath:tillpath /app/data
USER tillpath

EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=20s --retries=3 \
    CMD ["python", "-c", "import sys, urllib.request; sys.exit(urllib.request.urlopen('http://127.0.0.1:8000/api/health', timeout=4).status != 200)"]

# Applies the migrations, then serves.
CMD ["tillpath", "serve", "--host", "0.0.0.0", "--port", "8000"]
