;;;; The CPU a campaign worker runs on. A projected plan keeps its threads on the CPU its
;;;; top-level task starts on (CPL:*KEEP-PLANS-ON-ONE-CPU*); two workers starting their runs on
;;;; the same CPU would then share it for the run while the other waits idle. So each worker
;;;; process keeps to a CPU of its own, its slot's among those the tool may use, and its plans
;;;; with it.

(in-package :cram-plans-demo)

(defparameter *pin-workers* t
  "When true, each campaign worker runs on one CPU, the one of its slot among those it may use
\(PIN-TO-SLOT-CPU), unless the worker's environment has CRAM_PLANS_PIN_WORKERS=0 (read when the
worker starts, not when the saved core was built).")

(defun slot-cpu (slot cpus)
  "The CPU of worker SLOT among CPUS: slots take them in turn."
  (and cpus (nth (mod slot (length cpus)) cpus)))

(defun pin-to-slot-cpu (slot)
  "With *PIN-WORKERS*, keep this worker process on the CPU of SLOT (SLOT-CPU of the CPUs it may
use) when it may use more than one. Returns the CPU, or NIL when it was left free. Called
before any plan thread starts, so that they all run there."
  (let* ((mask (and *pin-workers* (not (equal (uiop:getenv "CRAM_PLANS_PIN_WORKERS") "0"))
                    (cpl::thread-cpu-mask)))
         (cpus (and mask (cpl::mask-cpus mask)))
         (cpu (and (rest cpus) (slot-cpu slot cpus))))
    (when (and cpu (cpl::set-thread-cpu-mask (cpl::cpu-mask cpu)))
      cpu)))
