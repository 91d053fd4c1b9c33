#pragma once
/// \file
/// Publishing a finished run directory to S3 so that a reader never sees a half-published
/// result (internal to the worker).
///
/// Layout under the publication prefix `s3://bucket/prefix` (the prefix may be empty):
///
///     objects/<sha256><ext>                     every file of the run, content-addressed
///     runs/<run>/manifests/<sha256>.json        publication manifests, content-addressed,
///                                               create-only
///     runs/<run>/CURRENT                        the pointer: names the run's manifest
///
/// Order, and why a reader is safe: (1) every file (data files and the local manifests) is
/// uploaded as an object whose key is its SHA-256 plus its extension, skipped when HEAD finds
/// the key already there with the same size, so at-least-once re-publishing uploads nothing
/// new; (2) then one publication manifest per cell and last one for the run is created
/// create-only; (3) only then the pointer is written. A reader who follows the pointer finds
/// a manifest whose every entry was stored before the manifest, and the manifest before the
/// pointer. A failure anywhere before (3) leaves the previous pointer (or none) untouched:
/// what was uploaded is unreferenced and re-used by the next attempt.
///
/// A publication manifest (JSON, keys sorted, two-space indent, trailing newline; keys inside
/// it are relative to the publication prefix, so the same run has the same manifest under
/// any prefix):
///
///     { "format": "csgtile.publication/1", "run": "<run>",
///       "scope": "cells/3_4",                       // "" for the run's whole directory
///       "local_manifest": "cells/3_4/manifest.json",
///       "files": { "<relative path>": {"key": "objects/<sha>.glb", "sha256": "<hex>",
///                                       "size": 123}, ... },
///       "cells": [ {"local_manifest": "...", "scope": "...", "key":
///       "runs/<run>/manifests/<sha>.json",
///                   "sha256": "<hex>"}, ... ] }     // run manifest only, in plan order
///
/// A cell's `files` are the plan's paths under its scope (the directory holding its local
/// manifest), its local manifest included; the run's `files` are every path of the plan.
/// The pointer is JSON too: {"format": "csgtile.pointer/1", "manifest": "<key>",
/// "run": "<run>", "sha256": "<hex of the manifest>"}; its `manifest` key is relative to the
/// prefix as well.
///
/// Create-only: a manifest key that already holds the same bytes is a no-op; one that holds
/// other bytes is a ResultInvalid "publish conflict" and is never overwritten (S3's
/// `If-None-Match: *` is not relied on: HEAD, then GET to compare). An object key that exists
/// with another size is the same conflict. Only the pointer is ever replaced, and only when
/// its bytes change.
///
/// Concurrent publishers of the same run write identical objects and manifests; the pointer
/// is last-writer-wins (fencing who may publish is the job runner's business).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "csgtile/worker/errors.h"
#include "fetch/fetch.h"

namespace csgtile::worker::publish {

/// What to publish: files of a local run directory, by relative path ('/'-separated).
struct PublishPlan {
  std::filesystem::path root;          ///< the local run directory
  std::vector<std::string> objects;    ///< relative paths of data files (any order)
  std::vector<std::string> manifests;  ///< relative paths of manifest files, cells first, run
                                       ///< manifest last (at least the run manifest)
};

/// What publishing did. Counts cover content objects and publication manifests, not the
/// pointer; on a failure they tell how far it got.
struct PublishReport {
  std::size_t uploaded = 0;          ///< objects and manifests PUT by this call
  std::size_t skipped_existing = 0;  ///< found already published (same size / same bytes)
  std::uint64_t bytes = 0;           ///< bytes PUT (pointer included)
  std::string pointer_key;           ///< bucket-relative key of the pointer; set once written
  std::string manifest_key;          ///< bucket-relative key of the run's publication manifest
  bool pointer_changed = false;      ///< the pointer was (re)written; false when it already
                                     ///< named this manifest
};

/// Publishes `plan` under `s3_prefix` ("s3://bucket" or "s3://bucket/prefix") as run
/// `run_name`, in the order and with the guarantees described at the top of this file.
///
/// Before any request: `run_name` must be one safe key segment, the prefix a valid bucket plus
/// a safe key, every relative path a safe key (is_safe_key: no "..", no leading '/', no empty
/// or "." segments, no control or other characters outside [A-Za-z0-9._-]) naming a regular
/// file that resolves inside `plan.root` (symbolic links included), each path listed once,
/// and at least one manifest — else InputInvalid naming the bad part; an unreadable file is Io.
/// Every file is hashed before the first upload and checked again as it is read for upload
/// (a file that changed meanwhile is Io).
///
/// S3 errors come from fetch's s3_put/s3_head/s3_get: transient ones are retried there and
/// end as Network (retryable), refusals such as HTTP 403 for a wrong secret are FetchRefused
/// (not retried); a create-only conflict is ResultInvalid. On any failure the pointer is not
/// written and `report.pointer_key` stays empty.
///
/// Cost: one HEAD per distinct file content, one PUT per missing one; a HEAD (+ GET when the
/// key exists with the same size) and possibly a PUT per manifest and for the pointer. Files
/// are read whole, one at a time, for upload. Concurrent calls are safe (see the top of this
/// file); the pointer is last-writer-wins.
Failure publish_run_to_s3(const PublishPlan& plan, const std::string& s3_prefix,
                          const std::string& run_name, const fetch::Policy& policy,
                          PublishReport& report);

/// The plan for a finished run directory: every regular file under `root`, in path order,
/// leaving out names that start with '.' (write_file_atomic's temporary files). Files named
/// `manifest.json` are the manifests: those below the root (the cells') first, in path
/// order, the root's `manifest.json` last; every other file is a data object. InputInvalid
/// when the root has no `manifest.json`; Io when the directory cannot be read.
Failure plan_run_directory(const std::filesystem::path& root, PublishPlan& plan);

/// The bucket-relative key of `run_name`'s pointer under `s3_prefix`, for readers and tests.
/// InputInvalid when the prefix or the name is not safe.
Failure pointer_key(const std::string& s3_prefix, const std::string& run_name, std::string& key);

}  // namespace csgtile::worker::publish
