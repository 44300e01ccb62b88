;;;; Sweeps in the replay: what a motion's path hit becomes an overlay of the step the motion
;;;; led to, drawn as the moving link's path (red from the first contact on) and the contact.

(in-package :cram-viewer)

(defun name-text (x)
  (if (stringp x) x (string-downcase (princ-to-string x))))

(defun sweep-overlay (sweep)
  "The JSON overlay of SWEEP (an URDF-PROJ:SWEEP)."
  (obj "type" "sweep"
       "motion" (urdf-proj:sweep-motion sweep)
       "moving" (or (urdf-proj:sweep-moving-link sweep) (name-text (urdf-proj:sweep-moving sweep)))
       "hit" (format nil "~a~@[ (~a)~]" (name-text (urdf-proj:sweep-hit sweep)) (urdf-proj:sweep-hit-link sweep))
       "fraction" (urdf-proj:sweep-fraction sweep)
       "point" (urdf-proj:sweep-point sweep)
       "path" (urdf-proj:sweep-path sweep)
       "text" (urdf-proj:sweep-description sweep)))

(defun note-sweep (sweep)
  "Keep SWEEP for the step its motion leads to (see *RECORD-RUNS*); its JSON (SWEEP-OVERLAY) is
made when the step is sent or written (OVERLAY-JSON)."
  (when *record-runs*
    (note-overlay (obj "type" "sweep" "sweep" sweep))))

(pushnew 'note-sweep urdf-proj:*sweep-hooks*)
