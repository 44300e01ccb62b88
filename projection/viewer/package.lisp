;;;; The browser viewer of the belief state (CRAM-VIEWER): scene descriptions, run recording
;;;; and replay (system cram-plans/replay, loaded with cram-plans), the web server and the
;;;; page (system cram-plans/viewer, loaded on first use by BTR:VIEWER or BTR:DEBUG-WINDOW).

(defpackage :cram-viewer
  (:nicknames :btr-viewer)
  (:use :cl)
  (:local-nicknames (:native :cram-native))
  (:export
   ;; scene descriptions and states
   #:object-descriptor #:world-scene #:world-state #:mesh-table
   ;; recording
   #:*record-runs* #:*max-recorded-runs* #:*max-steps-per-run* #:*max-recorded-steps*
   #:*max-runs-with-costmaps* #:recorded-runs #:last-run
   #:find-run #:clear-runs #:run-id #:run-steps #:run-label #:run-root #:step-label
   #:step-index #:step-failed-p #:record-motion #:run-json #:step-object-pose
   ;; overlays
   #:show-costmap #:show-poses #:show-target #:clear-overlays #:overlays
   ;; the viewer
   #:viewer #:stop-viewer #:viewer-url #:viewer-running-p #:*viewer-port* #:*viewer-host*
   #:*start-viewer-from-debug-window* #:watched-world
   ;; replays on disk
   #:write-replay #:replay-html))

;; (btr:viewer ...) is the user's entry point (see CRAM-VIEWER:VIEWER).
(export (intern "VIEWER" :cram-bullet-reasoning) :cram-bullet-reasoning)
