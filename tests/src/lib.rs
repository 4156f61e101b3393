//! Test-only package: insta snapshot tests and end-to-end tests live in .
