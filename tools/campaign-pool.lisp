;;;; The runs of a campaign that its workers take one at a time. A pool file lists the runs in
;;;; order; a worker claims the run at position P by linking its tag file (naming its slot and
;;;; generation) to claims/P, which the file system does at once or not at all: the link fails
;;;; when another worker has claimed P. A worker that finishes early takes the next unclaimed
;;;; run, so the workers of a campaign end together however long their runs take, and the
;;;; claims of a worker that died are found by its tag in the claim files.

(in-package :cram-plans-demo)

(defun write-pool (directory indices)
  "Write the pool of the run INDICES (in the order they are to be taken) into DIRECTORY, with
an empty claims directory; returns the pool file's path (a string)."
  (let ((pool (namestring (merge-pathnames "pool.indices" directory))))
    (ensure-directories-exist (claims-directory pool))
    (write-indices pool (coerce indices 'simple-vector))
    pool))

(defun claims-directory (pool)
  "The directory of the claim files of the pool file POOL."
  (merge-pathnames "claims/" (make-pathname :name nil :type nil :defaults pool)))

(defun claim-tag (slot generation)
  "The text a claim file of the worker of SLOT and GENERATION holds."
  (format nil "~d ~d" slot generation))

(defun claim-file (pool position)
  "The path of the claim file of the run at POSITION of the pool file POOL."
  (namestring (merge-pathnames (princ-to-string position) (claims-directory pool))))

(defun tag-file (pool tag)
  "The path of the tag file holding TAG, beside the claims of the pool file POOL."
  (namestring (merge-pathnames (format nil "tag-~a" (substitute #\- #\Space tag))
                               (claims-directory pool))))

(defun pool-claimer (pool slot generation)
  "A function returning, each time it is called, the index of the next run of the pool file
POOL that this worker (SLOT, GENERATION) claimed, or NIL when every run of the pool is
claimed. Runs are claimed in the pool's order."
  (let* ((indices (read-indices pool))
         (tag (claim-tag slot generation))
         (tag-file (tag-file pool tag))
         (position 0))
    (with-open-file (s tag-file :direction :output :if-exists :supersede)
      (write-string tag s))
    (lambda ()
      (loop while (< position (length indices))
            do (let ((p position))
                 (incf position)
                 (when (handler-case
                           (progn (sb-posix:link tag-file (claim-file pool p)) t)
                         (sb-posix:syscall-error (e)
                           (if (= (sb-posix:syscall-errno e) sb-posix:eexist)
                               nil
                               (error e))))
                   (return (svref indices p))))))))

(defun pool-claims (pool slot generation)
  "The indices of the runs of the pool file POOL that the worker of SLOT and GENERATION
claimed, in the pool's order."
  (let ((indices (read-indices pool))
        (tag (claim-tag slot generation)))
    (loop for p below (length indices)
          for file = (claim-file pool p)
          when (let ((text (with-open-file (s file :if-does-not-exist nil)
                             (and s (read-line s nil)))))
                 (equal text tag))
            collect (svref indices p))))

(defun run-source (indices pool slot generation)
  "A function returning the index of the next run a worker makes, or NIL when it is done: the
runs INDICES in order, then (with the pool file POOL) the runs it claims from the pool."
  (let ((claim (and pool (pool-claimer pool slot generation))))
    (lambda ()
      (if indices
          (pop indices)
          (and claim (funcall claim))))))
